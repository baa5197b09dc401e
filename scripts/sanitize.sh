#!/usr/bin/env bash
# Builds the project with AddressSanitizer + UndefinedBehaviorSanitizer in ./build-asan and runs
# the whole test suite there. Any finding fails (UBSan does not recover).
set -euo pipefail
cd "$(dirname "$0")/.."
# The Python module is left out: an instrumented extension cannot load into an uninstrumented
# interpreter (its tests run in the main build).
# -O1, as AddressSanitizer's documentation advises: the CGAL-heavy sources compile in about 0.6x
# of -O2's time under the instrumentation (the build is most of this stage's time).
cmake -S . -B build-asan -DCMAKE_BUILD_TYPE=RelWithDebInfo -DPEELCD_SANITIZE=ON -DPEELCD_PYTHON=OFF \
      -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -DNDEBUG" -DCMAKE_C_FLAGS_RELWITHDEBINFO="-O1 -DNDEBUG"
cmake --build build-asan -j "$(nproc)"
export ASAN_OPTIONS=detect_leaks=1:abort_on_error=1
export LSAN_OPTIONS=suppressions=$PWD/tests/lsan.supp
export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
# The adversarial narrow-phase test runs 100,000 cases in the plain build; 10,000 here, where
# each is ~10x slower, check the same code for memory and UB errors.
export PEELCD_ADVERSARIAL_CASES=10000
# The long sweeps against exact references (proximity and depth over the geometry classes, the
# World's far poses, compute coverage against the rasterizer, the GPU selection, the pairs-only
# request, the volume's random poses) run every third case here
# (tests/stride.h); the plain build runs every case.
export PEELCD_TEST_STRIDE=3
# The GL test cases run on OSMesa here; the plain build runs them on the three stacks. Over EGL
# (llvmpipe, zink) the same cases run the same peelcd code through another driver (2/3 of the
# instrumented suite's time); peelcd's EGL code runs instrumented in the contexts tests, the
# goldens on every stack and the command-line tests. Left to the plain build as well: the device
# check (scripts/device-check.sh runs the goldens, calibrate and bench commands that the golden
# and command-line tests run here) and the viewer (Chromium's page; its dump is the CLI's).
ctest --test-dir build-asan --output-on-failure -j 2 -E '^(gl egl-(llvmpipe|zink):|device check:|viewer:)'
