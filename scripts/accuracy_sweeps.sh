#!/usr/bin/env bash
# Regenerates the sweeps of docs/accuracy.md (CSV, summaries, heat maps, run-time plot) and
# rewrites its tables (scripts/accuracy_tables.py). Needs a built ./build/peelcd and
# python3-matplotlib. About 2 minutes on 2 cores.
set -euo pipefail
cd "$(dirname "$0")/.."
out=docs/accuracy
mkdir -p "$out"
scene=fixtures/scenes/bunny_dragon.json
run() {  # run NAME ARGS...: summary to $out/NAME.txt, rows to $out/NAME.csv
  local name=$1; shift
  ./build/peelcd sweep "$scene" "$@" --csv "$out/$name.csv" | tee "$out/$name.txt"
}
# The paper's pipeline peels the whole overlap box: the paper's modes with --cull box.
run paper   --res 128,256 --ids unique,paper --mode paper --cull box
run beat    --res 128,256 --ids paper,ring --mode alternate,full --slope 0,1 --cull box
run fused   --res 128,256 --ids paper,ring --mode full --views 3 --cull box,contact
run alt3    --res 128,256 --ids paper,ring --mode alternate --views 3 --cull box,contact
run cull    --res 128,256 --ids ring --mode full,alternate --views 1 --cull box,contact
run default --res 512 --ids ring --mode full,alternate --views 3
run views2  --res 128,256,512 --ids ring --mode full,alternate --views 2
# One CSV for the plots: every configuration once.
{ head -1 "$out/paper.csv"; for f in paper beat fused alt3 cull default views2; do tail -n +2 "$out/$f.csv"; done; } > "$out/all.csv"
"${PYTHON:-/usr/bin/python3}" scripts/plot_sweep.py "$out/all.csv" "$out/plots"
"${PYTHON:-/usr/bin/python3}" scripts/accuracy_tables.py docs/accuracy.md "$out"
