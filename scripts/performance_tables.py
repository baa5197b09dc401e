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
    """{method: [median, miss, false, xCGAL, xFCL, xfloor]} from a `peelcd bench` table."""
    out = {}
    for line in open(path):
        m = re.match(r"^(peelcd .*?|CGAL .*?|FCL .*?|floor: .*?)\s{2,}(\S.*)$", line.rstrip())
        if m:
            out[m.group(1)] = m.group(2).split()
    return out


def bench_default_table(path):
    b = bench_methods(path)
    rows = ["| method | median ms | miss | false | x CGAL | x FCL | x floor | x own floor |",
            "|---|---|---|---|---|---|---|---|"]
    for name, v in b.items():
        if name.startswith("floor"):
            continue
        rows.append("| %s | %s |" % (name, " | ".join(v + [""] * (7 - len(v)))))
    rows.append("| floor: one bare draw of the overlap box's triangles, 3 / 2 / 1 views | %s / %s / %s | | | | | | |" % (
        b["floor: 1 bare draw x 3 views"][0], b["floor: 1 bare draw x 2 views"][0], b["floor: 1 bare draw x 1 view"][0]))
    rows.append("| floor: one bare draw of the culled triangles, 3 / 2 / 1 views | %s / %s / %s | | | | | | |" % (
        b["floor: culled, 1 draw x 3 views"][0], b["floor: culled, 1 draw x 2 views"][0],
        b["floor: culled, 1 draw x 1 view"][0]))
    return "\n".join(rows)


def bench_scenes_table(p1, p2):
    b1, b2 = bench_methods(p1), bench_methods(p2)
    rows = ["| | test1 ms | miss | x CGAL | x FCL | x floor | test2 ms | miss | x CGAL | x FCL | x floor |",
            "|" + "---|" * 11]
    for name in b1:
        if name.startswith("floor"):
            continue
        v1, v2 = b1[name], b2[name]
        if name.startswith("peelcd"):
            rows.append("| %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s |" % (
                name, v1[0], v1[1], v1[3], v1[4], v1[5], v2[0], v2[1], v2[3], v2[4], v2[5]))
        else:
            rows.append("| %s | %s | %s | | | | %s | %s | | | |" % (name, v1[0], v1[1], v2[0], v2[1]))
    return "\n".join(rows)


def peeler_table(paths):
    """Single-pass against multi-pass, side by side in each benchmark run."""
    rows = ["| scene, configuration | single-pass ms | multi-pass ms | ratio |", "|---|---|---|---|"]
    for label, path in paths:
        b = bench_methods(path)
        for single, multi in (("peelcd default (3 views)", "peelcd default, multi-pass"),
                              ("peelcd paper config", "peelcd paper config, multi-pass")):
            s, m = float(b[single][0]), float(b[multi][0])
            rows.append("| %s, %s | %.2f | %.2f | %.2fx |" % (label, single[len("peelcd "):], s, m, s / m))
    return "\n".join(rows)


def phase_table(path):
    """Per phase of a dynamic scene: medians and the ratios of the default (3 views), 2 views and
    1 view with full peeling against CGAL, FCL and the floor with the same number of views."""
    lines = open(path).read().split("\n")
    start = next(i for i, l in enumerate(lines) if l.startswith("per phase"))
    head = lines[start + 1]  # "phase" in 7 characters, then one column per 10 (" %9s")
    cols = [head[i:i + 10].strip() for i in range(7, len(head), 10)]
    rows = ["| phase | CGAL ms | FCL ms | default ms | x CGAL | x FCL | x floor | 2 views ms | x CGAL | x FCL "
            "| x floor | 1 view ms | x CGAL | x FCL | x floor |", "|" + "---|" * 15]
    for line in lines[start + 2:]:
        if not line.startswith("("):
            continue
        parts = line.split()
        if parts[1:3] == ["no", "frames"]:
            continue
        v = dict(zip(cols, map(float, parts[1:])))
        cg, fc = v["CGAL"], v["FCL"]
        ratio = lambda a, b: "%.2f" % (a / b) if b > 0 else "-"
        cells = [parts[0], "%.2f" % cg, "%.2f" % fc]
        for config, floor in (("default", "floor x3"), ("2v full", "floor x2"), ("1v full", "floor x1")):
            t = v[config]
            cells += ["%.2f" % t, ratio(t, cg), ratio(t, fc), ratio(t, v[floor])]
        rows.append("| " + " | ".join(cells) + " |")
    return "\n".join(rows)


def targets_text(path):
    """The sentences of the targets section, from the default scene's benchmark."""
    b = bench_methods(path)
    d, f = b["peelcd default (3 views)"], b["peelcd 1 view, full peeling"]
    h = b["peelcd default, half the resolution"]
    t = b["peelcd 2 views, full peeling"]
    cg, fc = b["CGAL box_intersection_d + exact"][0], b["FCL 0.7 AABB tree built per frame"][0]
    return ("In this run the default (three views, full peeling, %s ms, %s miss) takes %sx CGAL (%s ms),\n"
            "%sx FCL (%s ms) and %sx the floor (%s ms; %sx the floor of the triangles it draws, %s ms);\n"
            "one view with full peeling (%s ms, %s miss) takes %sx CGAL, %sx FCL and %sx the floor\n"
            "(%s ms; %sx its own, %s ms); two views with full peeling (%s ms, %s miss) take %sx CGAL,\n"
            "%sx FCL and %sx the floor (%s ms; %sx its own, %s ms); the default at half the tile side\n"
            "(128²: %s ms, %s miss) takes %sx CGAL, %sx FCL and %sx the floor." % (
                d[0], d[1], d[3], cg, d[4], fc, d[5], b["floor: 1 bare draw x 3 views"][0], d[6],
                b["floor: culled, 1 draw x 3 views"][0],
                f[0], f[1], f[3], f[4], f[5], b["floor: 1 bare draw x 1 view"][0], f[6],
                b["floor: culled, 1 draw x 1 view"][0],
                t[0], t[1], t[3], t[4], t[5], b["floor: 1 bare draw x 2 views"][0], t[6],
                b["floor: culled, 1 draw x 2 views"][0], h[0], h[1], h[3], h[4], h[5]))


def main():
    doc, d = sys.argv[1], sys.argv[2]
    tables = {
        "simulate_test1": simulate_table(d + "/simulate_test1.txt"),
        "simulate_test2": simulate_table(d + "/simulate_test2.txt"),
        "bench_default": bench_default_table(d + "/bench_default.txt"),
        "bench_scenes": bench_scenes_table(d + "/bench_test1.txt", d + "/bench_test2.txt"),
        "phases_test1": phase_table(d + "/bench_test1.txt"),
        "phases_test2": phase_table(d + "/bench_test2.txt"),
        "targets": targets_text(d + "/bench_default.txt"),
        "peelers": peeler_table([("default scene 256²", d + "/bench_default.txt"),
                                 ("test1", d + "/bench_test1.txt"), ("test2", d + "/bench_test2.txt")]),
    }
    rewrite_marked(doc, tables, "performance_tables.py")


if __name__ == "__main__":
    main()
