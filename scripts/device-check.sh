#!/usr/bin/env bash
# The GPU path checked and measured in one command, on the EGL backend:
#   1. the golden suite on the hardware tier (--quick: the exact tier on llvmpipe), with the
#      GPU resolve (--resolve gpu) and with the host resolve (--coverage auto: by compute on a
#      GPU), and (not --quick) with the rasterizer's coverage;
#   2. the deep-texel scenes of the GPU resolve (a 1-texel tile on the default scene, both
#      resolves, every PCS compared with the certified filter off; with it, nothing missed);
#   3. run-to-run determinism: the same frames twice, batched with GPU selection and the GPU
#      resolve, every PCS and pair compared (detect --pcs --list);
#   4. peelcd bench on the default scene, the 400-ball pile, the 1.3M-triangle rigid and waving
#      spheres and the 1,000-ball pile (--quick: the default scene only), one thread per method:
#      the router's default rows and the image stage forced side by side with the CPU peers, and
#      the image-work table (host work, GL waits, GPU passes by timer queries, bytes, candidates);
#      on a machine with 9 or more cores, the large scenes' benches also time the World with 8
#      threads against one (--scaling 8: side by side, then the two alone, alternating, and the
#      lane model's bound for 8 lanes by the work's balance, to hold the measured ratio against);
#   5. peelcd calibrate --backend egl --write-costs (the router's cost models of this device and
#      the faster conservative coverage, raster or compute, in the record as costs.json), then
#      detect routing by them.
# Each step is stopped after STEP_TIMEOUT seconds (default 600), and counted as failed.
# It writes a dated record (device, driver, renderer, every command and its output) into
# docs/backends/<device>-<date>/ (or --out DIR) and prints a summary. Exit 1 if a check fails.
#
#   scripts/device-check.sh            # on a machine with a GPU and its EGL driver
#   scripts/device-check.sh --quick    # llvmpipe (no GPU), a few minutes; ctest runs it
#   PEELCD=path/to/peelcd scripts/device-check.sh   # a prebuilt binary (else ./build/peelcd,
#                                                   # built here without OSMesa if missing)
set -uo pipefail
cd "$(dirname "$0")/.."

quick=0
out=""
while [ $# -gt 0 ]; do
  case "$1" in
    --quick) quick=1 ;;
    --out) out="$2"; shift ;;
    -h|--help) sed -n '2,20p' "$0"; exit 0 ;;
    *) echo "device-check: unknown argument '$1' (expected --quick, --out DIR)" >&2; exit 2 ;;
  esac
  shift
done

bin="${PEELCD:-./build/peelcd}"
# A prebuilt binary elsewhere finds its fixtures and scripts in this checkout (a binary built
# here finds them from where it lies; one set by hand stands).
export PEELCD_DATA_DIR="${PEELCD_DATA_DIR:-$PWD}"
if [ ! -x "$bin" ]; then
  echo "device-check: no $bin: building the command line without OSMesa into build-device/"
  cmake -S . -B build-device -DCMAKE_BUILD_TYPE=Release -DPEELCD_WITH_OSMESA=OFF -DPEELCD_BUILD_TESTS=OFF >/dev/null &&
    cmake --build build-device -j "$(nproc)" --target peelcd >/dev/null || { echo "device-check: build failed" >&2; exit 1; }
  bin=./build-device/peelcd
fi

if [ "$quick" = 1 ]; then
  export LIBGL_ALWAYS_SOFTWARE=1  # Mesa's llvmpipe through EGL, even where a GPU is
  tier=exact
else
  tier=hardware
fi

# The device and the renderer, for the record's name.
# The first line of detect: "peelcd detect: FILE  (2 objects, BACKEND, RENDERER)".
renderer=$("$bin" detect fixtures/scenes/bunny_dragon.json --backend egl --stage image 2>&1 |
  sed -n '1s/^[^(]*([0-9]* objects, [^,]*, \(.*\))$/\1/p')
[ -n "$renderer" ] || { echo "device-check: the EGL backend did not come up:" >&2; "$bin" detect fixtures/scenes/bunny_dragon.json --backend egl --stage image >&2; exit 1; }
driver=""
if command -v nvidia-smi >/dev/null 2>&1; then
  driver=$(nvidia-smi --query-gpu=name,driver_version --format=csv,noheader 2>/dev/null | head -1)
fi
date=$(date -u +%Y-%m-%d)
slug=$(printf '%s' "${driver:-$renderer}" | cut -d, -f1 | tr 'A-Z' 'a-z' | sed 's/[^a-z0-9]\+/-/g; s/^-//; s/-$//' | cut -c1-40)
[ -n "$out" ] || out="docs/backends/${slug}-${date}"
mkdir -p "$out"
log="$out/log.txt"
: >"$log"
summary="$out/summary.md"
: >"$summary"
fails=0

say() { echo "$*" | tee -a "$log"; }
# Runs a command, its output into the log (and FILE when given), and says how it ended.
step() {
  local name="$1" file="$2"; shift 2
  local shown="$*"
  say "+ ${shown//$bin/peelcd}"  # the record names the command, not this machine's path to it
  local t0=$(date +%s%N) rc
  if [ -n "$file" ]; then
    timeout "${STEP_TIMEOUT:-600}" "$@" >"$out/$file" 2>&1; rc=$?; cat "$out/$file" >>"$log"
  else
    timeout "${STEP_TIMEOUT:-600}" "$@" >>"$log" 2>&1; rc=$?
  fi
  local ms=$((($(date +%s%N) - t0) / 1000000))
  local secs=$((ms / 1000)).$(printf '%03d' $((ms % 1000)))
  say "  -> exit $rc ($secs s)"
  printf '| %s | %s | %s s |\n' "$name" "$([ $rc = 0 ] && echo ok || echo "FAILED (exit $rc)")" "$secs" >>"$summary.steps"
  [ $rc = 0 ] || fails=$((fails + 1))
  return 0
}
: >"$summary.steps"
# A check that two outputs agree but for their timing and stage lines (the PCS, the pairs).
same() {
  local name="$1" x="$2" y="$3" timing='^timings\|^stage\|^  host work\|^  GPU passes'
  if diff <(grep -v "$timing" "$x") <(grep -v "$timing" "$y") >>"$log"; then
    printf '| %s | ok |  |\n' "$name" >>"$summary.steps"
  else
    say "$name: FAILED (the outputs differ: log.txt)"
    printf '| %s | FAILED |  |\n' "$name" >>"$summary.steps"
    fails=$((fails + 1))
  fi
}

say "peelcd device check, $date (UTC)$([ $quick = 1 ] && echo ', --quick (llvmpipe)')"
say "renderer: $renderer"
[ -n "$driver" ] && say "device, driver: $driver"
say "host: $(uname -srm), $(nproc) cores"
say "binary: $(basename "$bin"), peelcd $("$bin" --version 2>/dev/null | cut -d' ' -f2)"

# 1. The goldens, both resolves (the GPU resolve is what a GPU runs by default), then the
# conservative coverage by the rasterizer (auto is the compute pass on a GPU: the same layers).
for resolve in gpu host; do
  step "golden compare, $tier tier, --resolve $resolve" "golden_$resolve.txt" \
    "$bin" golden compare --backend egl --tier "$tier" --resolve "$resolve" --report "$out/golden-report-$resolve"
done
if [ "$quick" != 1 ]; then  # on llvmpipe ctest runs both ("golden ...: coverage by compute")
  # --coverage auto is compute on a GPU (without a cost file): the rasterizer's path by name.
  step "golden compare, $tier tier, --coverage raster" "golden_raster.txt" \
    "$bin" golden compare --backend egl --tier "$tier" --coverage raster --report "$out/golden-report-raster"
fi

# 2. Deep texels: every drawn triangle of both meshes in one texel (a 1-texel tile), the GPU
# resolve against the host's: the same PCS and pairs, nothing missed (the GPU's certified filter
# off: every overlapping couple, as the host lists them); then with the filter: nothing missed.
for resolve in gpu host; do
  step "deep texels (1-texel tile), --resolve $resolve" "deep_$resolve.txt" \
    "$bin" detect fixtures/scenes/bunny_dragon.json --backend egl --stage image --res 1 --views 3 --resolve "$resolve" \
    --no-gpu-filter --check --max-miss 0 --pcs --list
done
same "deep texels: GPU resolve = host resolve" "$out/deep_gpu.txt" "$out/deep_host.txt"
step "deep texels (1-texel tile), GPU resolve, certified filter" "deep_gpu_filtered.txt" \
  "$bin" detect fixtures/scenes/bunny_dragon.json --backend egl --stage image --res 1 --views 3 --resolve gpu \
  --check --max-miss 0

# 3. Determinism: the production path (batched views, GPU selection, GPU resolve) twice.
for run in 1 2; do
  step "determinism, run $run (3 views, image stage, GPU resolve)" "determinism_$run.txt" \
    "$bin" detect fixtures/scenes/bunny_dragon.json --backend egl --stage image --views 3 --resolve gpu --pcs --list
done
same "determinism: two runs, the same PCS and pairs" "$out/determinism_1.txt" "$out/determinism_2.txt"

# 4. Timings against the CPU peers, one thread per method.
if [ "$quick" = 1 ]; then
  step "bench, default scene" "bench_default.txt" "$bin" bench fixtures/scenes/bunny_dragon.json --backend egl --frames 3 --threads 1
else
  # The World's 8 threads against its one on the large scenes, where the host has the cores.
  scaling=()
  if [ "$(nproc)" -ge 9 ]; then scaling=(--scaling 8); fi
  step "bench, default scene" "bench_default.txt" "$bin" bench fixtures/scenes/bunny_dragon.json --backend egl --frames 30 --threads 1
  step "bench, 400-ball pile" "bench_pile400.txt" "$bin" bench crowd --objects 400 --backend egl --frames 6 --threads 1
  step "bench, 400-ball pile, the GPU's certified filter off" "bench_pile400_unfiltered.txt" \
    "$bin" bench crowd --objects 400 --backend egl --frames 6 --threads 1 --short --no-gpu-filter
  step "bench, rigid spheres 1.3M" "bench_spheres_1m.txt" "$bin" bench spheres --stacks 570 --backend egl --frames 4 --threads 1 --short "${scaling[@]}"
  # The deforming scenes, where the image stage should earn its place: the image-work table under
  # each bench says where its frame goes (host work, GL waits, GPU raster/compute/transfer by timer
  # queries, bytes uploaded, candidates to the host's exact test).
  step "bench, waving spheres 1.3M" "bench_spheres_wave_1m.txt" "$bin" bench spheres-wave --stacks 570 --backend egl --frames 4 --threads 1 --short "${scaling[@]}"
  step "bench, 1,000-ball pile" "bench_pile1000.txt" "$bin" bench crowd --objects 1000 --backend egl --frames 4 --threads 1 --short "${scaling[@]}"
  # The same deforming scenes with the conservative coverage by the rasterizer (the runs above:
  # auto, the compute pass on a GPU): the image-work tables' raster and compute columns.
  step "bench, waving spheres 1.3M, --coverage raster" "bench_spheres_wave_1m_raster.txt" \
    "$bin" bench spheres-wave --stacks 570 --backend egl --frames 4 --threads 1 --short --coverage raster
  step "bench, 1,000-ball pile, --coverage raster" "bench_pile1000_raster.txt" \
    "$bin" bench crowd --objects 1000 --backend egl --frames 4 --threads 1 --short --coverage raster
fi

# 5. The router's cost models of this device, written where detect --costs, $PEELCD_COSTS and
# Python's costs= load them, and loaded once.
if [ "$quick" = 1 ]; then
  step "calibrate" "calibrate_egl.txt" "$bin" calibrate --backend egl --repeat 3 --budgets 256 --large 0 \
    --write-costs "$out/costs.json"
else
  step "calibrate" "calibrate_egl.txt" "$bin" calibrate --backend egl --write-costs "$out/costs.json"
fi
step "detect with the fitted models (--costs)" "detect_costs.txt" \
  "$bin" detect fixtures/scenes/bunny_dragon.json --backend egl --costs "$out/costs.json" --check --max-miss 0

{
  echo "# Device check, $date"
  echo
  echo "Renderer \"$renderer\"${driver:+; device and driver: $driver}; host $(uname -m), $(nproc) cores."
  echo "Command: \`scripts/device-check.sh$([ $quick = 1 ] && echo ' --quick')\`; every output in log.txt beside this file."
  echo
  echo "| step | result | time |"
  echo "|---|---|---|"
  cat "$summary.steps"
} >"$summary"
rm -f "$summary.steps"
cat "$summary"
echo "device-check: $fails check(s) failed; the record is in $out/"
[ "$fails" = 0 ]
