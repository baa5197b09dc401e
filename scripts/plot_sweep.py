#!/usr/bin/env python3
"""Plots a `peelcd sweep` CSV: one miss-ratio heat map over (theta, phi) per configuration, and
run time against miss ratio for all configurations.

usage: plot_sweep.py SWEEP.csv OUT_DIR      (needs Debian's python3-matplotlib)
"""
import csv
import os
import re
import sys
from collections import defaultdict

import matplotlib
import matplotlib.ticker

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main(path, out_dir):
    rows = list(csv.DictReader(open(path)))
    by_config = defaultdict(list)
    for r in rows:
        by_config[r["config"]].append(r)
    os.makedirs(out_dir, exist_ok=True)

    # One colour scale for every heat map (0 to the worst miss of the whole sweep), so that maps of
    # different configurations compare by colour; cells centred on the sampled directions, the
    # ticks at those directions.
    worst_all = max((100 * float(r["miss_ratio"]) for r in rows), default=0.0)
    vmax = worst_all if worst_all > 0 else 1.0
    for config, rs in by_config.items():
        thetas = sorted({float(r["theta"]) for r in rs})
        phis = sorted({float(r["phi"]) for r in rs})
        grid = [[float("nan")] * len(thetas) for _ in phis]
        for r in rs:
            miss = 100 * float(r["miss_ratio"])
            i = phis.index(float(r["phi"]))
            if abs(float(r["phi"])) == 90:  # a pole is one direction: fill its whole row
                grid[i] = [miss] * len(thetas)
            else:
                grid[i][thetas.index(float(r["theta"]))] = miss
        avg = sum(100 * float(r["miss_ratio"]) for r in rs) / len(rs)
        dt = thetas[1] - thetas[0] if len(thetas) > 1 else 30.0
        dp = phis[1] - phis[0] if len(phis) > 1 else 30.0
        fig, ax = plt.subplots(figsize=(7, 4.2))
        im = ax.imshow(grid, origin="lower", aspect="auto", cmap="viridis", vmin=0, vmax=vmax,
                       extent=[thetas[0] - dt / 2, thetas[-1] + dt / 2, phis[0] - dp / 2, phis[-1] + dp / 2])
        fig.colorbar(im, ax=ax, label="miss ratio (%), one scale for the whole sweep")
        step_t = max(1, len(thetas) // 12)
        step_p = max(1, len(phis) // 10)
        ax.set_xticks(thetas[::step_t])
        ax.set_yticks(phis[::step_p])
        ax.xaxis.set_major_formatter(matplotlib.ticker.FuncFormatter(lambda v, _: f"{v:g}"))
        ax.yaxis.set_major_formatter(matplotlib.ticker.FuncFormatter(lambda v, _: f"{v:g}"))
        ax.set_xlabel("theta (degrees)")
        ax.set_ylabel("phi (degrees)")
        ax.set_title(f"{config}: average {avg:.2f}%", fontsize=10)
        fig.tight_layout()
        name = re.sub(r"[^A-Za-z0-9]+", "_", config).strip("_")
        fig.savefig(os.path.join(out_dir, f"heatmap_{name}.png"), dpi=110)
        plt.close(fig)

    # Run time against miss ratio: one numbered point per configuration, the key beside the plot
    # (labels on the points overlap when configurations cluster).
    points = []
    for config, rs in by_config.items():
        avg = sum(100 * float(r["miss_ratio"]) for r in rs) / len(rs)
        times = sorted(float(r["total_ms"]) for r in rs)
        points.append((times[len(times) // 2], avg, config))
    points.sort(key=lambda p: (p[1], p[0]))
    fig = plt.figure(figsize=(13, max(5.5, 0.19 * len(points) + 1.5)))
    ax = fig.add_axes([0.07, 0.16, 0.47, 0.74])
    cmap = plt.get_cmap("tab20")
    markers = "osD^vP*X"
    for k, (t, m, config) in enumerate(points, 1):
        ax.scatter([t], [m], s=36, color=cmap((k - 1) % 20), marker=markers[(k - 1) // 20 % len(markers)],
                   label=f"{k}: {config}  ({t:.3g} ms, {m:.2f}%)")
        ax.annotate(str(k), (t, m), fontsize=6, xytext=(3, 2), textcoords="offset points")
    ax.set_xlabel("median run time per frame (ms)")
    ax.set_ylabel("average miss ratio (%)")
    ax.set_xscale("log")
    ax.set_yscale("symlog", linthresh=0.1)  # the interesting configurations are below 1%
    ax.set_ylim(bottom=0, top=max(1.0, max(m for _, m, _ in points) * 1.5))
    times = sorted({t for t, _, _ in points})
    if len(times) <= 8:  # few configurations: the ticks at their times
        ax.xaxis.set_major_locator(matplotlib.ticker.FixedLocator(times))
        ax.xaxis.set_minor_locator(matplotlib.ticker.NullLocator())
    else:
        ax.xaxis.set_major_locator(matplotlib.ticker.LogLocator(subs=(1.0, 2.0, 3.0, 5.0)))
    ax.xaxis.set_major_formatter(matplotlib.ticker.FuncFormatter(lambda v, _: f"{v:.3g}"))
    ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
    lo, hi = min(times), max(times)
    ax.set_xlim(lo / 1.15, hi * 1.15)  # the points off the frame's edges
    plt.setp(ax.get_xticklabels(), rotation=30, ha="right")
    ax.set_title(f"run time against miss ratio ({len(points)} configurations; lower left is better)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(loc="upper left", bbox_to_anchor=(1.02, 1.0), fontsize=6.5, frameon=False,
              title="configuration (median time, average miss)", title_fontsize=7)
    fig.savefig(os.path.join(out_dir, "time_vs_miss.png"), dpi=110)
    plt.close(fig)


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2])
