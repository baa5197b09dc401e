#!/usr/bin/env python3
"""Rewrites the measured tables of docs/performance.md from the files scripts/performance.sh
writes (docs/performance/simulate_*.txt, bench_*.txt). Each table sits between
<!-- BEGIN name --> and <!-- END name --> markers; text outside the markers is left alone.

usage: performance_tables.py DOC DIR
"""
import re
import sys

from doc_tables import rewrite_marked


def simulate_rows(path):
    """Rows of the per-phase summary of `peelcd simulate`, ours and the paper's."""
    lines = open(path).read().split("\n")
    start = next(i for i, l in enumerate(lines) if l.startswith("summary"))
    rows = []
    for line in lines[start + 2:]:
        if not line.startswith("("):
            continue
        phase, ours, paper = (part.split() for part in line.split("|"))
        n, found, aabb, gpu, readback, cpu, total = ours
        rows.append("| %s | %s | %s | %.2f | %.1f | %.3f | %.2f | %.1f | %s |" % (
            phase[0], n, found, float(aabb), float(gpu), float(readback), float(cpu), float(total),
            " | ".join(paper)))
    return rows


def simulate_table(path):
    head = ("| phase | nCTP | found | AABB | GPU | readback | CPU | total "
            "| paper: nCTP | AABB | GPU | readback | CPU | total |\n|" + "---|" * 14)
    return head + "\n" + "\n".join(simulate_rows(path))


def bench_methods(path):
    """{method: [median, stage, miss, false, xCGAL, xFCL, xbest, xfloor]} from a `peelcd bench` table."""
    out = {}
    for line in open(path):
        m = re.match(r"^(peelcd .*?|CGAL.*?|FCL .*?|Embree .*?|Bullet .*?|floor: .*?)\s{2,}(\S.*)$", line.rstrip())
        if m:
            out[m.group(1)] = m.group(2).split()
    return out


def bench_table(path):
    """Every row of a `peelcd bench` table, with its header lines as a caption."""
    b = bench_methods(path)
    head = [l.rstrip() for l in open(path) if l.startswith(("peelcd bench:", "threads:", "World:", "router"))]
    rows = ["| method | median ms | stage ms | miss | false | x CGAL | x FCL | x best | x floor |",
            "|---|---|---|---|---|---|---|---|---|"]
    for name, v in b.items():
        rows.append("| %s | %s |" % (name, " | ".join(v + [""] * (8 - len(v)))))
    return "\n".join(["`" + h + "`" + "  " for h in head] + [""] + rows)


def main():
    doc, d = sys.argv[1], sys.argv[2]
    tables = {
        "simulate_test1": simulate_table(d + "/simulate_test1.txt"),
        "simulate_test2": simulate_table(d + "/simulate_test2.txt"),
    }
    for name in ("bench_default", "bench_default_2threads", "bench_test1", "bench_test2", "bench_crowd",
                 "bench_crowd_2threads", "bench_spheres", "bench_spheres_wave", "bench_spheres_1m",
                 "bench_spheres_1m_wave", "bench_pile1000", "bench_spheres_1m_2threads",
                 "bench_spheres_1m_wave_2threads", "bench_pile1000_2threads"):
        tables[name] = bench_table(d + "/" + name + ".txt")
    rewrite_marked(doc, tables, "performance_tables.py")


if __name__ == "__main__":
    main()
