#!/usr/bin/env bash
# Builds the libFuzzer targets with clang (ASan + UBSan) in ./build-fuzz and runs each from the
# seeds in fixtures/fuzz/. Usage: scripts/fuzz.sh [SCENE_RUNS [MESH_RUNS]]  (defaults 20000 and
# 3000 inputs, about a minute each here; a fixed seed, so a run is repeatable). New inputs go to
# build-fuzz/corpus/, crashes to build-fuzz/artifacts/. Time-bounded runs instead:
# scripts/fuzz.sh 0 0 with FUZZ_SECONDS=3600 (per target).
set -euo pipefail
cd "$(dirname "$0")/.."
scene_runs=${1:-20000}
mesh_runs=${2:-3000}
if ! command -v clang++ >/dev/null || ! ls /usr/lib/llvm-*/lib/clang/*/lib/linux/libclang_rt.fuzzer-x86_64.a >/dev/null 2>&1; then
  sudo_cmd=""; [ "$(id -u)" -ne 0 ] && sudo_cmd="sudo"
  $sudo_cmd apt-get update -q
  DEBIAN_FRONTEND=noninteractive $sudo_cmd apt-get install -y -q --no-install-recommends clang libclang-rt-14-dev
fi
# -O1, as libFuzzer's and AddressSanitizer's documentation use (scripts/sanitize.sh says why).
cmake -S . -B build-fuzz -DPEELCD_PYTHON=OFF -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ \
      -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -DNDEBUG" -DCMAKE_C_FLAGS_RELWITHDEBINFO="-O1 -DNDEBUG" \
      -DPEELCD_FUZZ=ON -DPEELCD_BUILD_TESTS=OFF
cmake --build build-fuzz -j "$(nproc)" --target fuzz_scene fuzz_mesh_detect
export ASAN_OPTIONS=detect_leaks=1
export LSAN_OPTIONS=suppressions=$PWD/tests/lsan.supp
export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
for target in scene mesh; do
  exe=build-fuzz/fuzz/fuzz_scene; runs=$scene_runs
  [ $target = mesh ] && exe=build-fuzz/fuzz/fuzz_mesh_detect && runs=$mesh_runs
  mkdir -p build-fuzz/corpus/$target build-fuzz/artifacts
  limit=(-runs="$runs"); [ "$runs" = 0 ] && limit=(-max_total_time="${FUZZ_SECONDS:-3600}")
  "$exe" -seed=1 "${limit[@]}" -max_len=65536 -timeout=20 -print_final_stats=1 \
         -artifact_prefix=build-fuzz/artifacts/ build-fuzz/corpus/$target fixtures/fuzz/$target
done
