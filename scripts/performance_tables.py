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
    """{method: [median, stage, miss, false, xCGAL, xFCL, xbest, xfloor]} from a `peelcd bench` table
    (its first table only: the tables after it, such as the image work per frame, name the same
    methods with other columns)."""
    out = {}
    for line in open(path):
        m = re.match(r"^(peelcd .*?|CGAL.*?|FCL .*?|Embree .*?|Bullet .*?|floor: .*?)\s{2,}(\S.*)$", line.rstrip())
        if m:
            out[m.group(1)] = m.group(2).split()
        elif out and not line.strip():
            break
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


PEERS = ("CGAL", "FCL", "Embree", "Bullet")


def standing_table(d, scenes):
    """Per bench scene: the World's median, the fastest peer row and the ratio; the World asking
    for pairs only (its row, where the run has one) against the same peer row."""
    rows = ["| scene | World (default) ms | fastest peer | its ms | World / peer | pairs only / peer |",
            "|---|---|---|---|---|---|"]
    for label, name in scenes:
        b = bench_methods(d + "/" + name + ".txt")
        world = float(b["peelcd default (World, stage auto)"][0])
        # Labelled variants ("scaled test", the plain setup of --audit) are no peer's default:
        # left out, as bench's x best does.
        peers = [(float(v[0]), k) for k, v in b.items()
                 if k.startswith(PEERS) and "scaled test" not in k and "(audit)" not in k]
        best_ms, best = min(peers)
        pairs = b.get("peelcd World, pairs only (stage auto)")
        pairs_ratio = "%.2f" % (float(pairs[0]) / best_ms) if pairs else "-"
        rows.append("| %s | %.2f | %s | %.2f | %.2f | %s |" % (label, world, best, best_ms, world / best_ms, pairs_ratio))
    return "\n".join(rows)


def audit_table(d, scenes):
    """The `audit:` lines of bench runs with --audit: each FCL, Embree and Bullet row against
    its library's plain setup, with the plain setup's misses and false pairs (its own test)."""
    rows = ["| scene | peer row | its ms | plain setup ms | row / plain | plain setup: miss, false pairs |",
            "|---|---|---|---|---|---|"]
    for label, name in scenes:
        b = bench_methods(d + "/" + name + ".txt")
        for line in open(d + "/" + name + ".txt"):
            m = re.match(r"^audit: (.*?) / the plain setup: (\S+) \(medians (\S+) / (\S+) ms", line)
            if m:
                library = m.group(1).split(" ")[0]
                plain = [v for k, v in b.items() if k.startswith(library) and k.endswith("plain setup (audit)")][0]
                rows.append("| %s | %s | %s | %s | %s | %s, %s |" % (label, m.group(1), m.group(3), m.group(4),
                                                                   m.group(2), plain[2], plain[3]))
    return "\n".join(rows)


def threads_table(d, scenes):
    """Per large scene: the World with one thread and with two in one run, twice (its --scaling
    pass: the two alone, alternating frame by frame; and its rows side by side with the others);
    each peer with one thread and with one per core, from the two runs."""
    rows = ["| scene | method | 1 thread ms | 2 threads ms | ratio | measured |", "|---|---|---|---|---|---|"]
    for label, one, two in scenes:
        b1, b2 = bench_methods(d + "/" + one + ".txt"), bench_methods(d + "/" + two + ".txt")
        m = re.search(r"^scaling: .*alternating frame by frame: [0-9.]+ \(medians ([0-9.]+) / ([0-9.]+) ms\)",
                      open(d + "/" + one + ".txt").read(), re.M)
        w2, w1 = float(m.group(1)), float(m.group(2))
        rows.append("| %s | peelcd default (World) | %.2f | %.2f | %.2f | one run, the two alone, alternating |" % (label, w1, w2, w2 / w1))
        s1, s2 = float(b1["peelcd default (World, stage auto)"][0]), float(b1["peelcd default, 2 threads"][0])
        rows.append("| %s | peelcd default (World) | %.2f | %.2f | %.2f | one run, side by side with the others |" % (label, s1, s2, s2 / s1))
        for k in b1:
            if not k.startswith(("FCL 0.7, deforming refit", "Embree", "Bullet")) or k not in b2:
                continue
            m1, m2 = float(b1[k][0]), float(b2[k][0])
            rows.append("| %s | %s | %.2f | %.2f | %.2f | two runs, side by side with the others |" % (label, k, m1, m2, m2 / m1))
    return "\n".join(rows)


def self_table(path):
    """The rows of a `peelcd bench cloth-self|cloth-crumpled` table."""
    lines = open(path).read().split("\n")
    caption = "`" + lines[0] + "`"
    rows = ["| method | median ms | ratio to the World | exact | found | missed | false |", "|---|---|---|---|---|---|---|"]
    for line in lines[2:]:
        m = re.match(r"^(\S.*?)\s{2,}(\d.*)$", line.rstrip())
        if m and not line.startswith("("):
            rows.append("| %s | %s |" % (m.group(1), " | ".join(m.group(2).split())))
    return caption + "\n\n" + "\n".join(rows)


def main():
    doc, d = sys.argv[1], sys.argv[2]
    tables = {
        "simulate_test1": simulate_table(d + "/simulate_test1.txt"),
        "simulate_test2": simulate_table(d + "/simulate_test2.txt"),
    }
    for name in ("bench_default", "bench_crowd", "bench_spheres", "bench_spheres_wave", "bench_pile1000"):
        tables[name] = bench_table(d + "/" + name + ".txt")
    tables["standing"] = standing_table(d, [
        ("default scene (bunny vs dragon)", "bench_default"), ("test1", "bench_test1"), ("test2", "bench_test2"),
        ("400-ball pile", "bench_crowd"), ("1,000-ball pile", "bench_pile1000"),
        ("rigid spheres, 330k each", "bench_spheres"), ("rigid spheres, 1.3M each", "bench_spheres_1m"),
        ("waving spheres, 330k each", "bench_spheres_wave"), ("waving spheres, 1.3M each", "bench_spheres_1m_wave")])
    tables["audit"] = audit_table(d, [
        ("default scene (bunny vs dragon)", "audit_default"), ("test1", "audit_test1"), ("test2", "audit_test2"),
        ("400-ball pile", "audit_crowd"), ("rigid spheres, 330k each", "audit_spheres"),
        ("waving spheres, 330k each", "audit_spheres_wave")])
    tables["threads"] = threads_table(d, [
        ("rigid spheres, 1.3M", "bench_spheres_1m", "bench_spheres_1m_2threads"),
        ("waving spheres, 1.3M", "bench_spheres_1m_wave", "bench_spheres_1m_wave_2threads"),
        ("1,000-ball pile", "bench_pile1000", "bench_pile1000_2threads")])
    tables["cloth_crumpled"] = self_table(d + "/cloth_crumpled.txt")
    tables["cloth_self"] = self_table(d + "/cloth_self.txt")
    rewrite_marked(doc, tables, "performance_tables.py")


if __name__ == "__main__":
    main()
