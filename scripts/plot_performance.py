#!/usr/bin/env python3
"""Plots of docs/performance.md from the CSVs of peelcd bench and peelcd simulate.

Usage: python3 scripts/plot_performance.py OUT_DIR BENCH_CSV... [--simulate SIM_CSV...]
  time_vs_miss.png: median ms per frame against miss ratio, one panel per bench CSV, with the
                    CGAL and FCL points and the bare-draw floors as lines.
  scaling.png:      per frame of each simulate CSV, total ms against the triangles drawn in the
                    ROIs, and the CPU + readback ms against nCTP.
"""
import csv
import os
import statistics
import sys

import matplotlib

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

    fig, axes = plt.subplots(1, len(benches), figsize=(5.5 * len(benches), 4.5), squeeze=False)
    for ax, path in zip(axes[0], benches):
        data = read_bench(path)
        for name, (ms, miss) in data.items():
            if name.startswith("floor"):
                ax.axhline(ms, ls=":", color="grey")
                ax.text(0.5, ms, " " + name, color="grey", fontsize=7, va="bottom")
                continue
            marker = "s" if name.startswith("CGAL") else ("^" if name.startswith("FCL") else "o")
            ax.scatter([100 * miss], [ms], marker=marker, s=40)
            ax.annotate(name, (100 * miss, ms), fontsize=7, xytext=(4, 3), textcoords="offset points")
        ax.set_xlabel("miss ratio (%)")
        ax.set_ylabel("median ms per frame")
        ax.set_title(os.path.basename(path).replace(".csv", ""))
        ax.set_yscale("log")
        ax.grid(True, which="both", alpha=0.3)
    fig.tight_layout()
    fig.savefig(os.path.join(out_dir, "time_vs_miss.png"), dpi=110)
    print("wrote", os.path.join(out_dir, "time_vs_miss.png"))

    if sims:
        fig, axes = plt.subplots(1, 2, figsize=(11, 4.5))
        for path in sims:
            rows = [r for r in csv.DictReader(open(path)) if int(r["rois_peeled"]) > 0]
            label = os.path.basename(path).replace(".csv", "")
            tris = [int(r["triangles_uploaded"]) + int(r["triangles_indexed"]) for r in rows]
            axes[0].scatter(tris, [float(r["total_ms"]) for r in rows], s=14, label=label)
            axes[1].scatter([int(r["nctp"]) for r in rows],
                            [float(r["cpu_ms"]) + float(r["readback_ms"]) for r in rows], s=14, label=label)
        axes[0].set_xlabel("triangles drawn in the ROI views (all views)")
        axes[0].set_ylabel("total ms per frame")
        axes[1].set_xlabel("nCTP (exact colliding pairs)")
        axes[1].set_ylabel("CPU + readback ms per frame")
        for ax in axes:
            ax.grid(True, alpha=0.3)
            ax.legend()
        fig.tight_layout()
        fig.savefig(os.path.join(out_dir, "scaling.png"), dpi=110)
        print("wrote", os.path.join(out_dir, "scaling.png"))


if __name__ == "__main__":
    main()
