#!/usr/bin/env bash
# Regenerates docs/performance/ and the tables of docs/performance.md: the two dynamic scenes (peelcd simulate), the benchmarks
# against CGAL, FCL and the bare-draw floor (peelcd bench), and the plots. Needs a built
# ./build/peelcd and python3-matplotlib (Debian's /usr/bin/python3). About half a minute on 2 cores;
# run it on a quiet machine: every number is a median of frames measured side by side.
set -euo pipefail
cd "$(dirname "$0")/.."
out=docs/performance
mkdir -p "$out"
for t in test1 test2; do
  ./build/peelcd simulate "$t" --frames 40 --csv "$out/simulate_$t.csv" > "$out/simulate_$t.txt"
  ./build/peelcd bench "$t" --frames 12 --csv "$out/bench_$t.csv" > "$out/bench_$t.txt"
done
./build/peelcd bench fixtures/scenes/bunny_dragon.json --frames 15 --csv "$out/bench_default.csv" > "$out/bench_default.txt"
PY=/usr/bin/python3; [ -x "$PY" ] || PY=python3
"$PY" scripts/plot_performance.py "$out" "$out/bench_default.csv" "$out/bench_test1.csv" "$out/bench_test2.csv" \
  --simulate "$out/simulate_test1.csv" "$out/simulate_test2.csv"
"$PY" scripts/performance_tables.py docs/performance.md "$out"
