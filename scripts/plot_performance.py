#!/usr/bin/env python3
"""Plots of docs/performance.md from the CSVs of peelcd bench and peelcd simulate.

Usage: python3 scripts/plot_performance.py OUT_DIR BENCH_CSV... [--simulate SIM_CSV...]
  time_vs_miss.png: median ms per frame against miss ratio, one panel per bench CSV, with the
                    CGAL and FCL points and the bare-draw floors as lines.
  scaling.png:      per frame of each simulate CSV that peeled a ROI, total ms against the
                    triangles drawn in the ROIs, and the CPU + readback ms against nCTP (not
                    written when no frame peeled one).
"""
import csv
import os
import statistics
import sys

import matplotlib

import matplotlib.ticker  # noqa: E402
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def read_bench(path):
    rows = list(csv.DictReader(open(path)))
    methods = []
    for r in rows:
        if r["method"] not in methods:
            methods.append(r["method"])
    out = {}
    for m in methods:
        rs = [r for r in rows if r["method"] == m]
        exact = sum(int(r["nctp"]) for r in rs)
        found = sum(int(r["found"]) for r in rs)
        out[m] = (statistics.median(float(r["ms"]) for r in rs), 1.0 - found / exact if exact else 0.0)
    return out


def main():
    args = sys.argv[1:]
    if len(args) < 2:
        sys.exit(__doc__)
    out_dir = args[0]
    sims = []
    if "--simulate" in args:
        i = args.index("--simulate")
        sims = args[i + 1:]
        args = args[:i]
    benches = args[1:]
    os.makedirs(out_dir, exist_ok=True)

    # One panel per scene; every method has one colour and marker in all panels, named once in a
    # shared legend (labels on the points overlap where methods cluster).
    titles = {"bench_default": "default scene (bunny / dragon)", "bench_test1": "test1 (raptor, 40 balls)",
              "bench_test2": "test2 (cloth, 40 objects)", "bench_crowd": "crowd (400 balls)"}
    data_all = [(path, read_bench(path)) for path in benches]
    methods = []
    for _, data in data_all:
        for name in data:
            if not name.startswith("floor") and name not in methods:
                methods.append(name)
    cmap = plt.get_cmap("tab20")
    style = {}
    for k, name in enumerate(methods):
        marker = "s" if name.startswith("CGAL") else ("^" if name.startswith("FCL") else "o")
        style[name] = (cmap(k % 20), marker)
    cols = 2 if len(benches) > 1 else 1
    rows = (len(benches) + cols - 1) // cols
    fig, axes = plt.subplots(rows, cols, figsize=(15, 4.6 * rows), squeeze=False)
    handles = {}
    for ax, (path, data) in zip(axes.flat, data_all):
        top = 0.0
        for name, (ms, miss) in data.items():
            if name.startswith("floor"):
                ax.axhline(ms, ls=":", color="grey")
                ax.text(1.0, ms, name + " ", color="grey", fontsize=7, va="bottom", ha="right",
                        transform=ax.get_yaxis_transform())
                continue
            colour, marker = style[name]
            handles[name] = ax.scatter([100 * miss], [ms], marker=marker, s=44, color=colour, label=name)
            top = max(top, 100 * miss)
        ax.set_xlabel("miss ratio against the exact reference (%)")
        ax.set_ylabel("median time per frame (ms)")
        stem = os.path.basename(path).replace(".csv", "")
        ax.set_title(titles.get(stem, stem))
        ax.set_xlim(left=-0.02 * max(top, 1.0), right=max(top, 1.0) * 1.08)
        ax.set_yscale("log")
        ax.yaxis.set_major_formatter(matplotlib.ticker.FuncFormatter(lambda v, _: f"{v:g}"))
        ax.yaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
        ax.grid(True, which="both", alpha=0.3)
    for ax in list(axes.flat)[len(data_all):]:
        ax.axis("off")
    fig.suptitle("time per frame against miss ratio, one thread per method (peelcd bench --threads 1)")
    fig.legend([handles[m] for m in methods if m in handles], [m for m in methods if m in handles],
               loc="center right", fontsize=8, frameon=False, title="method")
    fig.tight_layout(rect=(0, 0, 0.78, 0.96))
    fig.savefig(os.path.join(out_dir, "time_vs_miss.png"), dpi=110)
    print("wrote", os.path.join(out_dir, "time_vs_miss.png"))

    # Only frames that peeled a ROI have points: where the router sent every ROI to the exact path
    # (llvmpipe, no GPU) there are none, and no chart is written rather than an empty one.
    peeled = {path: [r for r in csv.DictReader(open(path)) if int(r["rois_peeled"]) > 0] for path in sims}
    if sims and not any(peeled.values()):
        print("scaling.png: not written: no frame of", ", ".join(sims), "peeled a ROI (the router sent every ROI to "
              "the exact path); run simulate with --stage image, or on a GPU")
    if any(peeled.values()):
        fig, axes = plt.subplots(1, 2, figsize=(11, 4.5))
        for path in sims:
            rows = peeled[path]
            if not rows:
                continue
            label = os.path.basename(path).replace(".csv", "")
            tris = [int(r["triangles_uploaded"]) + int(r["triangles_indexed"]) for r in rows]
            axes[0].scatter(tris, [float(r["total_ms"]) for r in rows], s=14, label=label)
            axes[1].scatter([int(r["nctp"]) for r in rows],
                            [float(r["cpu_ms"]) + float(r["readback_ms"]) for r in rows], s=14, label=label)
        axes[0].set_xlabel("triangles drawn in the ROI views (all views)")
        axes[0].set_ylabel("total ms per frame")
        axes[1].set_xlabel("nCTP (exact colliding pairs)")
        axes[1].set_ylabel("CPU + readback ms per frame")
        axes[0].set_title("frame time against the triangles drawn (peelcd simulate)")
        axes[1].set_title("narrow phase and read-back against nCTP")
        for a in axes:
            a.set_xlim(left=0)
            a.set_ylim(bottom=0)
        for ax in axes:
            ax.grid(True, alpha=0.3)
            ax.legend()
        fig.tight_layout()
        fig.savefig(os.path.join(out_dir, "scaling.png"), dpi=110)
        print("wrote", os.path.join(out_dir, "scaling.png"))


if __name__ == "__main__":
    main()
