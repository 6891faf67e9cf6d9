#!/usr/bin/env bash
# README command 2: set up, build, and run every test:
#   1. the Release build's ctest suite (native GoogleTest, CLI over the mesh set, Blender tests),
#   2. the same native tests built with AddressSanitizer + UndefinedBehaviorSanitizer,
#   3. the libFuzzer targets for a bounded time from their seed corpora.
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/setup.sh
./scripts/build.sh

echo "== tests (Release)"
ctest --test-dir build --output-on-failure -j2

echo "== tests (AddressSanitizer + UndefinedBehaviorSanitizer)"
cmake -S . -B build-asan -DCMAKE_BUILD_TYPE=RelWithDebInfo -DQGP_SANITIZE=ON >/dev/null
cmake --build build-asan -j"$(nproc)"
export ASAN_OPTIONS="detect_leaks=1:abort_on_error=1:strict_string_checks=1"
export LSAN_OPTIONS="suppressions=$PWD/tests/sanitizer/lsan.supp"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
# Real-mesh sweeps (suites named *Meshes*) and benchmarks run in the Release pass only.
ctest --test-dir build-asan --output-on-failure -j2 -L native -E 'Meshes|Bench'

echo "== fuzzing (${QGP_FUZZ_SECONDS:-45} s per target)"
unset ASAN_OPTIONS LSAN_OPTIONS UBSAN_OPTIONS
CC=clang CXX=clang++ cmake -S . -B build-fuzz -DCMAKE_BUILD_TYPE=RelWithDebInfo -DQGP_FUZZ=ON >/dev/null
cmake --build build-fuzz -j"$(nproc)" --target fuzz_read_mesh fuzz_capi_arrays
for target in read_mesh capi_arrays; do
  work=$(mktemp -d)
  build-fuzz/bin/fuzz_$target -max_total_time="${QGP_FUZZ_SECONDS:-45}" -timeout=10 -rss_limit_mb=4096 \
    -artifact_prefix="$work/" "$work" "tests/fuzz/corpus/$target" 2>&1 | grep -E "^Done|ERROR|SUMMARY" || true
  if ls "$work"/crash-* "$work"/timeout-* "$work"/leak-* "$work"/oom-* >/dev/null 2>&1; then
    echo "fuzz_$target found a failing input:"; ls "$work"; exit 1
  fi
done
echo "== all tests passed"
