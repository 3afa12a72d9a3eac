# Sourced by test_cli.sh and test_distributed.sh (which set exe, src, tmp and fail): a run of
# uniaxial_block whose load increment falls below its minimum must exit 1 with one error line
# and keep its completed steps in a results file marked failed.
# Usage: check_failed_run [LAUNCHER...]   (the run is LAUNCHER... "$exe" run ...)
check_failed_run() {
  "$@" "$exe" run "$src/apps/scenes/uniaxial_block.json" --out "$tmp/bad.h5" --set boundary.3.offset=-1.5 \
    --set solver.min_increment=0.01 > /dev/null 2> "$tmp/err.log"
  local rc=$?
  [ $rc -eq 1 ] || fail "failed run exited $rc, expected 1"
  [ "$(wc -l < "$tmp/err.log")" -eq 1 ] || fail "expected one error line, got: $(cat "$tmp/err.log")"
  grep -q "^depthfem: error: $src/apps/scenes/uniaxial_block.json: load increment fell below min_increment" "$tmp/err.log" || fail "error line: $(cat "$tmp/err.log")"
  "$exe" info "$tmp/bad.h5" > "$tmp/info2.log" || fail "info on the failed run exited $?"
  grep -q "status: failed" "$tmp/info2.log" || fail "failed run not marked failed"
  grep -Eq "steps: [1-9]" "$tmp/info2.log" || fail "failed run kept no steps"
}
