"""Shared by scripts/performance_tables.py and scripts/accuracy_tables.py: rewrites the text
between <!-- BEGIN name --> and <!-- END name --> markers of a Markdown file."""
import re
import sys


def rewrite_marked(doc, tables, tool):
    """Replaces each marked block `name` of `doc` by tables[name]; exits naming `tool` if a
    block's markers are missing. Text outside the markers is left alone."""
    text = open(doc).read()
    for name, table in tables.items():
        pattern = re.compile(r"(<!-- BEGIN %s -->\n).*?(\n<!-- END %s -->)" % (name, name), re.S)
        if not pattern.search(text):
            sys.exit("%s: %s has no markers for %s" % (tool, doc, name))
        text = pattern.sub(lambda m: m.group(1) + table + m.group(2), text)
    open(doc, "w").write(text)
    print("rewrote %d tables in %s" % (len(tables), doc))
