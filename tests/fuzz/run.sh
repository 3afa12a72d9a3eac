#!/usr/bin/env bash
# Sanitizer pass: builds the file readers, the command line and the core and apps tests with
# AddressSanitizer + UBSan (clang), runs those tests, then a bounded libFuzzer pass of each fuzz
# target (every file reader; the results-file readers; the command line) from its seed corpus.
# Any sanitizer report, crash, hang or unlocated error message fails; one line per target gives
# the inputs run.
# Usage: tests/fuzz/run.sh [SECONDS_PER_TARGET]   (from the repository root; default 45)
set -euo pipefail
cd "$(dirname "$0")/../.."
seconds=${1:-45}
jobs=$(nproc 2>/dev/null || echo 2)
# -O1 without debug information, only the targets below: 12.6 CPU minutes on the 2-core machine
# (-O2 -g with all of test_apps took 21); -O0 compiles in 8.3 but fuzzes 8 times slower.
cmake -S . -B build-sanitize -DCMAKE_BUILD_TYPE=Sanitize -DCMAKE_CXX_FLAGS_SANITIZE=-O1 \
  -DCMAKE_C_FLAGS_SANITIZE=-O1 -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_C_COMPILER=clang \
  -DDEPTHFEM_SANITIZE=ON -DDEPTHFEM_BUILD_BENCH=OFF > /dev/null
cmake --build build-sanitize -j"$jobs" --target sanitizer_pass
export ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
export LSAN_OPTIONS=suppressions=$PWD/tests/fuzz/lsan.supp  # leaks inside HDF5 on damaged files
build-sanitize/tests/test_core --gtest_brief=1
build-sanitize/tests/test_inputs --gtest_brief=1
bash tests/apps/test_cli.sh build-sanitize/apps/depthfem .
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
# Text inputs up to 4 KiB; results files up to their largest seed's size (124 KB, most of it
# chunks of zeros that HDF5 allocates 4 KiB at a time).
for target in inputs results command_line; do
  mkdir "$work/$target"
  cp tests/fuzz/corpus/"$target"/* "$work/$target/"
  max_len=4096
  [ "$target" = results ] && max_len=$(du -b tests/fuzz/corpus/results/* | sort -n | tail -1 | cut -f1)
  status=0
  (cd "$work" && "$OLDPWD/build-sanitize/tests/fuzz_$target" -max_total_time="$seconds" \
    -max_len="$max_len" -timeout=10 -rss_limit_mb=4096 -print_final_stats=1 "$work/$target" \
    > "$work/$target.log" 2>&1) || status=$?
  runs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$work/$target.log")
  if ((status != 0)); then
    tail -40 "$work/$target.log"
    echo "fuzz_$target: FINDING after ${runs:-?} inputs (exit $status); the input is above" >&2
    exit 1
  fi
  echo "fuzz_$target: ${runs:-?} inputs in $seconds s, no crash, sanitizer report or unlocated message"
done
