#!/usr/bin/env python3
"""Rewrites the tables of docs/accuracy.md from the summaries `peelcd sweep` printed into
docs/accuracy/*.txt (scripts/accuracy_sweeps.sh). Each table sits between <!-- BEGIN name -->
and <!-- END name --> markers; text outside the markers is left alone.

    accuracy_tables.py docs/accuracy.md docs/accuracy
"""
import re
import sys

from doc_tables import rewrite_marked

SWEEPS = ["paper", "beat", "fused", "alt3", "cull", "default", "views2"]

# The paper's Fig. 8 (average / maximum / minimum miss ratio over its views).
PAPER_FIG8 = {
    "256 paper": "5.02% / 12.7% / 0.65%",
    "256 unique": "22.61% / 29.31% / 14.98%",
    "128 paper": "12.32% / 20.52% / 5.86%",
    "128 unique": "(not given)",
}

DEFAULT = "ring full slope=1 views=3 cull=contact"


def sweep_rows(d):
    """{configuration: [avg, max, min, false, candidates, eff, median, mean]}, first seen wins."""
    rows = {}
    for name in SWEEPS:
        for line in open("%s/%s.txt" % (d, name)):
            m = re.match(r"^(\d+ \S+ \S+ slope=\S+ views=\d cull=\S+)\s+(\S.*)$", line.rstrip())
            if m and m.group(1) not in rows:
                rows[m.group(1)] = m.group(2).split()
    return rows


def key(res, ids, mode, slope, views, cull):
    return "%d %s %s slope=%g views=%d cull=%s" % (res, ids, mode, slope, views, cull)


def config_table(rows, configs, with_cull):
    head = "| res | IDs | mode | slope | views |" + (" cull |" if with_cull else "") + \
        " avg miss | max miss | min miss | candidates | eff. | median ms |"
    out = [head, "|" + "---|" * (head.count("|") - 1)]
    for c in configs:
        k = key(*c)
        v = rows[k]
        cells = [str(c[0]), c[1], c[2], "%g" % c[3], str(c[4])] + ([c[5]] if with_cull else []) + \
            [v[0], v[1], v[2], v[4], v[5], "%.1f" % float(v[6])]
        if k.endswith(DEFAULT):
            cells = ["**%s**" % x for x in cells]
        out.append("| " + " | ".join(cells) + " |")
    return "\n".join(out)


def fig8_table(rows):
    out = ["| configuration | paper avg / max / min | peelcd avg / max / min | median ms |", "|---|---|---|---|"]
    for res, ids, label in ((256, "paper", "non-unique (paper) IDs"), (256, "unique", "unique IDs"),
                            (128, "paper", "non-unique (paper) IDs"), (128, "unique", "unique IDs")):
        v = rows[key(res, ids, "paper", 0, 1, "box")]
        out.append("| %d^2, %s | %s | %s / %s / %s | %.1f |" % (
            res, label, PAPER_FIG8["%d %s" % (res, ids)], v[0], v[1], v[2], float(v[6])))
    return "\n".join(out)


def main():
    doc, d = sys.argv[1], sys.argv[2]
    rows = sweep_rows(d)
    box = "box"
    beat = [(256, "paper", "paper", 0, 1, box), (256, "paper", "alternate", 1, 1, box),
            (256, "paper", "full", 0, 1, box), (256, "paper", "full", 1, 1, box),
            (256, "ring", "paper", 0, 1, box), (256, "ring", "alternate", 1, 1, box),
            (256, "ring", "full", 0, 1, box), (256, "ring", "full", 1, 1, box),
            (256, "paper", "alternate", 1, 3, box), (256, "paper", "full", 1, 3, box),
            (256, "ring", "alternate", 1, 3, box), (256, "ring", "full", 1, 3, box),
            (128, "paper", "paper", 0, 1, box), (128, "ring", "alternate", 1, 1, box),
            (128, "ring", "full", 1, 1, box), (128, "ring", "alternate", 1, 3, box),
            (128, "ring", "full", 1, 3, box)]
    cull = []
    for res in (256, 128):
        for mode, views in (("full", 1), ("alternate", 1), ("alternate", 3), ("full", 3)):
            for c in ("box", "contact"):
                cull.append((res, "ring", mode, 1, views, c))
    cull += [(512, "ring", "full", 1, 3, "contact"), (512, "ring", "alternate", 1, 3, "contact")]
    views = []
    for res in (128, 256, 512):
        for mode in ("full", "alternate"):
            for v in (3, 2, 1):
                if key(res, "ring", mode, 1, v, "contact") in rows:
                    views.append((res, "ring", mode, 1, v, "contact"))
    tables = {
        "fig8": fig8_table(rows),
        "beat": config_table(rows, beat, False),
        "cull": config_table(rows, cull, True),
        "views": config_table(rows, views, True),
    }
    rewrite_marked(doc, tables, "accuracy_tables.py")


if __name__ == "__main__":
    main()
