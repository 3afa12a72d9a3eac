#!/usr/bin/env bash
# End-to-end checks of the depthfem command line: exit codes, the one-line error, partial results.
# Usage: test_cli.sh PATH/TO/depthfem SOURCE_DIR
source "$(dirname "$0")/preamble.sh"

"$exe" run "$src/apps/scenes/uniaxial_block.json" --out "$tmp/ok.h5" > "$tmp/ok.log" 2>&1 || fail "uniaxial_block run exited $?"
grep -q "^step    0" "$tmp/ok.log" || fail "no progress line"
grep -q "= linear solve" "$tmp/ok.log" || fail "no timing table"
"$exe" info "$tmp/ok.h5" > "$tmp/info.log" || fail "info exited $?"
grep -q "status: completed" "$tmp/info.log" || fail "info does not report completion"
[ -f "$tmp/ok.xmf" ] && [ -f "$tmp/ok.xdmf2" ] || fail "no XDMF sidecars"

source "$src/tests/apps/failed_run.sh"
check_failed_run

"$exe" run "$src/apps/scenes/uniaxial_block.json" > /dev/null 2> "$tmp/usage.log"
[ $? -eq 2 ] || fail "missing --out must be a usage error (exit 2)"
grep -q "^depthfem: error: run needs --out" "$tmp/usage.log" || fail "usage message: $(cat "$tmp/usage.log")"
"$exe" run "$src/apps/scenes/uniaxial_block.json" --out "$tmp/x.h5" --threads zero > /dev/null 2>&1
[ $? -eq 2 ] || fail "--threads zero must be a usage error"
"$exe" run "$src/apps/scenes/uniaxial_block.json" --out "$tmp/x.h5" --set bodies.0.material.C9=1 > /dev/null 2> "$tmp/key.log"
[ $? -eq 1 ] || fail "unknown key must exit 1"
grep -q "bodies\[0\].material.C9: unknown key" "$tmp/key.log" || fail "unknown key not named: $(cat "$tmp/key.log")"
"$exe" info "$tmp/nothing.h5" > /dev/null 2>&1 && fail "info on a missing file must fail"

# A run killed mid-way: its progress lines reached the log file while it ran (stdout is a file),
# and its results file keeps the completed steps and the timing of the phases so far.
"$exe" run "$src/apps/scenes/sliding_blocks.json" --out "$tmp/killed.h5" \
  --set solver.initial_increment=0.005 --set solver.max_increment=0.005 > "$tmp/killed.log" 2>&1 &
pid=$!
for _ in $(seq 1200); do
  grep -q "^step    1" "$tmp/killed.log" && break
  kill -0 $pid 2> /dev/null || break
  sleep 0.1
done
kill -0 $pid 2> /dev/null || fail "the 200-step run ended (or never printed step 1) before it was killed"
kill -9 $pid
wait $pid 2> /dev/null
grep -q "^step    1" "$tmp/killed.log" || fail "no progress line reached the log file during the run"
"$exe" info "$tmp/killed.h5" > "$tmp/info3.log" || fail "info on the killed run exited $?"
grep -q "status: running" "$tmp/info3.log" || fail "killed run: $(cat "$tmp/info3.log")"
grep -q "linear solve" "$tmp/info3.log" || fail "the killed run kept no timing"
# Inputs are never overwritten: --out naming the scene (here through a second name) is refused.
cp "$src/apps/scenes/uniaxial_block.json" "$tmp/scene.json"
ln -s scene.json "$tmp/alias.h5"
"$exe" run "$tmp/scene.json" --out "$tmp/alias.h5" > /dev/null 2> "$tmp/in.log"
[ $? -eq 1 ] || fail "--out equal to the scene must exit 1"
grep -q "would overwrite the input" "$tmp/in.log" || fail "--out = scene: $(cat "$tmp/in.log")"
cmp -s "$tmp/scene.json" "$src/apps/scenes/uniaxial_block.json" || fail "the scene was overwritten"

# A second writer on the same results file is refused while the first runs, and leaves its file.
# The first runs 100 times its scene's duration (minutes), so that it is still writing when the
# second starts, however loaded the machine (a finished run closes its file, which shrinks it).
"$exe" run "$src/apps/scenes/falling_bars.json" --out "$tmp/busy.h5" --threads 1 \
  --set dynamic.duration=200 > "$tmp/first.log" 2>&1 &
first=$!
# Up to a minute for its first step: a loaded machine can take seconds to start it.
for _ in $(seq 1200); do
  grep -q "^step    0" "$tmp/first.log" && [ -f "$tmp/busy.h5" ] && break
  sleep 0.05
done
grep -q "^step    0" "$tmp/first.log" || fail "the first writer printed no step in a minute"
"$exe" info "$tmp/busy.h5" > "$tmp/before.log" || fail "the first writer's file: $(cat "$tmp/before.log")"
steps_of() { sed -n 's/^  steps: \([0-9]*\),.*/\1/p' "$1"; }
"$exe" run "$src/apps/scenes/uniaxial_block.json" --out "$tmp/busy.h5" > /dev/null 2> "$tmp/busy.log"
rc=$?
kill -0 $first 2> /dev/null || fail "the first writer ended before the second was refused"
# Its file is the first run's still, as far as it got (its size is no test: HDF5 may trim the
# file's end at a flush).
"$exe" info "$tmp/busy.h5" > "$tmp/after.log" || fail "the first writer's file no longer reads: $(cat "$tmp/after.log")"
[ "$(grep ' mesh: ' "$tmp/after.log")" = "$(grep ' mesh: ' "$tmp/before.log")" ] || fail "the second writer replaced the first's file"
[ "$(steps_of "$tmp/after.log")" -ge "$(steps_of "$tmp/before.log")" ] || fail "the first writer's file lost steps"
grep -q "status: running" "$tmp/after.log" || fail "the first writer's file: $(cat "$tmp/after.log")"
kill -9 $first 2> /dev/null; wait $first 2> /dev/null
[ $rc -eq 1 ] || fail "a second writer must exit 1, got $rc"
grep -q "busy.h5: is being written by another depthfem run (process $first)" "$tmp/busy.log" || fail "second writer: $(cat "$tmp/busy.log")"

# Every error is one line, even for a key holding a newline; --threads takes a positive integer.
"$exe" run "$tmp/scene.json" --out "$tmp/y.h5" --set "$(printf 'a\nb')=1" > /dev/null 2> "$tmp/nl.log"
[ "$(wc -l < "$tmp/nl.log")" -eq 1 ] || fail "error over several lines: $(cat "$tmp/nl.log")"
"$exe" run "$tmp/scene.json" --out "$tmp/y.h5" --threads 3x > /dev/null 2>&1
[ $? -eq 2 ] || fail "--threads 3x must be a usage error"

# A restart continues a static run from a step of its file: the uniaxial block from step 1 of
# ok.h5 (load 0.5) needs two more steps; --step needs --restart, and a missing step is an error.
"$exe" run "$src/apps/scenes/uniaxial_block.json" --out "$tmp/re.h5" --restart "$tmp/ok.h5" --step 1 \
  > "$tmp/re.log" 2>&1 || fail "restart exited $?: $(cat "$tmp/re.log")"
grep -q "^restart from step 1 of .* at load 0.5$" "$tmp/re.log" || fail "restart line: $(head -1 "$tmp/re.log")"
"$exe" info "$tmp/re.h5" | grep -q "steps: 2, last load/time 1," || fail "restart did not end at load 1 in two steps"
"$exe" run "$src/apps/scenes/uniaxial_block.json" --out "$tmp/re2.h5" --step 1 > /dev/null 2>&1
[ $? -eq 2 ] || fail "--step without --restart must be a usage error"
"$exe" run "$src/apps/scenes/uniaxial_block.json" --out "$tmp/re2.h5" --restart "$tmp/ok.h5" --step 9 \
  > /dev/null 2> "$tmp/re2.err"
[ $? -eq 1 ] && [ "$(wc -l < "$tmp/re2.err")" -eq 1 ] || fail "missing step: $(cat "$tmp/re2.err")"
grep -q "has no step 9" "$tmp/re2.err" || fail "missing step message: $(cat "$tmp/re2.err")"

# A dynamic run goes on from its last step: the viscoelastic bars by Newmark to 0.05 s, then on to
# 0.1 s (dynamic.duration set longer) in five more steps.
bars="$src/apps/scenes/falling_bars_viscoelastic.json"
"$exe" run "$bars" --out "$tmp/dy.h5" --set dynamic.integrator=newmark --set dynamic.duration=0.05 \
  > /dev/null 2>&1 || fail "dynamic run exited $?"
"$exe" run "$bars" --out "$tmp/dy2.h5" --restart "$tmp/dy.h5" --set dynamic.integrator=newmark \
  --set dynamic.duration=0.1 > "$tmp/dy2.log" 2>&1 || fail "dynamic restart exited $?: $(tail -1 "$tmp/dy2.log")"
grep -q "^restart from step 4 of .* at t = 0.05 s$" "$tmp/dy2.log" || fail "dynamic restart line: $(head -1 "$tmp/dy2.log")"
"$exe" info "$tmp/dy2.h5" | grep -q "steps: 5, last load/time 0.1," || fail "dynamic restart did not end at 0.1 s in five steps"
echo "cli: all checks passed"
