#!/usr/bin/env bash
# Regenerates docs/performance/ and the tables of docs/performance.md: the router's calibration
# (peelcd calibrate), the two dynamic scenes (peelcd simulate), the benchmarks against CGAL, FCL
# Embree, Bullet and the bare-draw floor (peelcd bench: the default scene, test1, test2 and a 400-ball pile,
# all with one thread per method; the default scene and the crowd again with one per core; the
# scale scenes: crossing spheres of 330k and 1.3M triangles, rigid and waving, and a 1,000-ball
# pile), and the plots. Needs a built ./build/peelcd and python3-matplotlib (Debian's /usr/bin/python3).
# About ten minutes on 2 cores; run it on a quiet machine: every number is a median of frames
# measured side by side.
set -euo pipefail
cd "$(dirname "$0")/.."
out=docs/performance
mkdir -p "$out"
./build/peelcd calibrate --backend osmesa --large 72 144 288 570 > "$out/calibrate_osmesa.txt"
./build/peelcd calibrate --backend cpu --large 0 > "$out/calibrate_cpu.txt"
for t in test1 test2; do
  ./build/peelcd simulate "$t" --frames 40 --csv "$out/simulate_$t.csv" > "$out/simulate_$t.txt"
  ./build/peelcd bench "$t" --frames 12 --threads 1 --csv "$out/bench_$t.csv" > "$out/bench_$t.txt"
done
scene=fixtures/scenes/bunny_dragon.json
./build/peelcd bench "$scene" --frames 30 --threads 1 --csv "$out/bench_default.csv" > "$out/bench_default.txt"
./build/peelcd bench "$scene" --frames 30 > "$out/bench_default_2threads.txt"
./build/peelcd bench crowd --objects 400 --frames 6 --threads 1 --csv "$out/bench_crowd.csv" > "$out/bench_crowd.txt"
./build/peelcd bench crowd --objects 400 --frames 6 > "$out/bench_crowd_2threads.txt"
# The scale scenes: two crossing spheres of 330k and 1.3M triangles each, rigid and with a wave
# over their vertices, and a pile of 1,000 balls (the World, the frame API's router and image
# stage, the peers, the floors: --short).
./build/peelcd bench spheres --frames 6 --threads 1 --short > "$out/bench_spheres.txt"
./build/peelcd bench spheres-wave --frames 6 --threads 1 --short > "$out/bench_spheres_wave.txt"
./build/peelcd bench spheres --stacks 570 --frames 8 --threads 1 --short --scaling 2 > "$out/bench_spheres_1m.txt"
./build/peelcd bench spheres-wave --stacks 570 --frames 8 --threads 1 --short --scaling 2 > "$out/bench_spheres_1m_wave.txt"
./build/peelcd bench crowd --objects 1000 --frames 8 --threads 1 --short --scaling 2 > "$out/bench_pile1000.txt"
# (--scaling 2: the World again with two threads, side by side with the others, then the two
# World rows alone over the frames, alternating: the threads table's World rows.) The large
# scenes again with one thread per core, for the peers' two-thread times.
./build/peelcd bench spheres --stacks 570 --frames 4 --short > "$out/bench_spheres_1m_2threads.txt"
./build/peelcd bench spheres-wave --stacks 570 --frames 4 --short > "$out/bench_spheres_1m_wave_2threads.txt"
./build/peelcd bench crowd --objects 1000 --frames 4 --short > "$out/bench_pile1000_2threads.txt"
# The audit: each peer's rows beside its library as a plain user sets it up (--audit: FCL, Embree
# and Bullet, each in a file of its own; --short: the World's rows and the peers), one thread.
for a in "$scene --frames 30:default" "test1 --frames 12:test1" "test2 --frames 12:test2" \
         "crowd --objects 400 --frames 6:crowd" "spheres --frames 6:spheres" "spheres-wave --frames 6:spheres_wave"; do
  # shellcheck disable=SC2086  # the scene's arguments, split
  ./build/peelcd bench ${a%%:*} --threads 1 --short --audit > "$out/audit_${a##*:}.txt"
done
# Self-collision (one thread): the folding sheet and the crumpled cloth (--audit: Embree's self
# rows against its plain setup); the volume.
./build/peelcd bench cloth-self --frames 8 --audit > "$out/cloth_self.txt"
./build/peelcd bench cloth-crumpled --frames 6 --audit > "$out/cloth_crumpled.txt"
./build/peelcd bench volume --frames 3 > "$out/volume.txt"
# The queries: penetration depth against bisection, the least distance against FCL.
./build/peelcd bench depth --frames 3 > "$out/depth.txt"
./build/peelcd bench distance --frames 3 > "$out/distance.txt"
PY=/usr/bin/python3; [ -x "$PY" ] || PY=python3
"$PY" scripts/plot_performance.py "$out" "$out/bench_default.csv" "$out/bench_test1.csv" "$out/bench_test2.csv" \
  "$out/bench_crowd.csv" --simulate "$out/simulate_test1.csv" "$out/simulate_test2.csv"
"$PY" scripts/performance_tables.py docs/performance.md "$out"
