#!/usr/bin/env bash
# Sanitizer pass: builds the file readers, the command line and the core and apps tests with
# AddressSanitizer + UBSan (clang), runs those tests, then a bounded libFuzzer pass over every file
# reader from the seed corpus. Any sanitizer report, crash or unlocated error message fails.
# Usage: tests/fuzz/run.sh [SECONDS_OF_FUZZING]   (from the repository root; default 120)
set -euo pipefail
cd "$(dirname "$0")/../.."
seconds=${1:-120}
jobs=$(nproc 2>/dev/null || echo 2)
cmake -S . -B build-sanitize -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER=clang++ \
  -DCMAKE_C_COMPILER=clang -DDEPTHFEM_SANITIZE=ON -DDEPTHFEM_BUILD_BENCH=OFF > /dev/null
cmake --build build-sanitize -j"$jobs" --target fuzz_inputs test_core test_apps depthfem
export ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
build-sanitize/tests/test_core
build-sanitize/tests/test_apps --gtest_filter='SceneFile*'
bash tests/apps/test_cli.sh build-sanitize/apps/depthfem .
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cp tests/fuzz/corpus/inputs/* "$work/"
build-sanitize/tests/fuzz_inputs -max_total_time="$seconds" -max_len=4096 -timeout=10 \
  -rss_limit_mb=4096 -print_final_stats=1 "$work" 2>&1 | tail -15
