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

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main(path, out_dir):
    rows = list(csv.DictReader(open(path)))
    by_config = defaultdict(list)
    for r in rows:
        by_config[r["config"]].append(r)
    os.makedirs(out_dir, exist_ok=True)

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
        fig, ax = plt.subplots(figsize=(7, 4.2))
        im = ax.imshow(grid, origin="lower", aspect="auto", cmap="viridis", vmin=0,
                       extent=[thetas[0], thetas[-1] + (thetas[1] - thetas[0] if len(thetas) > 1 else 30),
                               phis[0] - 5, phis[-1] + 5])
        fig.colorbar(im, ax=ax, label="miss ratio (%)")
        ax.set_xlabel("theta (degrees)")
        ax.set_ylabel("phi (degrees)")
        ax.set_title(f"{config}: average {avg:.2f}%")
        fig.tight_layout()
        name = re.sub(r"[^A-Za-z0-9]+", "_", config).strip("_")
        fig.savefig(os.path.join(out_dir, f"heatmap_{name}.png"), dpi=110)
        plt.close(fig)

    fig, ax = plt.subplots(figsize=(7, 4.5))
    for config, rs in by_config.items():
        avg = sum(100 * float(r["miss_ratio"]) for r in rs) / len(rs)
        times = sorted(float(r["total_ms"]) for r in rs)
        median = times[len(times) // 2]
        ax.scatter([median], [avg], s=40)
        ax.annotate(config, (median, avg), fontsize=7, xytext=(4, 3), textcoords="offset points")
    ax.set_xlabel("median run time per frame (ms)")
    ax.set_ylabel("average miss ratio (%)")
    ax.set_xscale("log")
    ax.set_yscale("symlog", linthresh=0.1)  # the interesting configurations are below 1%
    ax.set_title("run time against miss ratio")
    ax.grid(True, alpha=0.3)
    fig.tight_layout()
    fig.savefig(os.path.join(out_dir, "time_vs_miss.png"), dpi=110)
    plt.close(fig)


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2])
