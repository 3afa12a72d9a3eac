#!/usr/bin/env bash
# The files a run writes beside its results cannot be redirected, are never an input of the
# run, and stay valid when a write fails: planted links on the helper files' names, inputs named
# like them, and file-size limits (ulimit -f) that cut the run at every stage of its writing.
# Usage: test_helper_files.sh PATH/TO/depthfem SOURCE_DIR
source "$(dirname "$0")/preamble.sh"
scene=$src/apps/scenes/uniaxial_block.json

# Links planted on every name a run used to write through (the lock, the staging file, the
# sidecars' temporaries): the lock's is refused, the others are not used; the victim is intact.
mkdir "$tmp/links"
echo "precious" > "$tmp/victim"
ln -s ../victim "$tmp/links/.r.h5.lock"
"$exe" run "$scene" --out "$tmp/links/r.h5" > /dev/null 2> "$tmp/lock.err"
[ $? -eq 1 ] || fail "a link planted on the lock file must be refused (exit 1)"
grep -q "^depthfem: error: .*r.h5: the lock file .*\.r\.h5\.lock is a symbolic link" "$tmp/lock.err" ||
  fail "planted lock link: $(cat "$tmp/lock.err")"
rm "$tmp/links/.r.h5.lock"
for name in .r.h5.partial r.xmf.tmp r.xdmf2.tmp r.xmf r.xdmf2; do ln -s ../victim "$tmp/links/$name"; done
"$exe" run "$scene" --out "$tmp/links/r.h5" > /dev/null 2> "$tmp/links.err" ||
  fail "run beside planted links: $(cat "$tmp/links.err")"
[ "$(cat "$tmp/victim")" = "precious" ] || fail "a planted link redirected a write to the victim"
for sidecar in r.xmf r.xdmf2; do
  [ -f "$tmp/links/$sidecar" ] && [ ! -L "$tmp/links/$sidecar" ] ||
    fail "$sidecar is still the planted link"
done
# A hard link to another file as the lock file is refused too.
mkdir "$tmp/hard"
ln "$tmp/victim" "$tmp/hard/.r.h5.lock"
"$exe" run "$scene" --out "$tmp/hard/r.h5" > /dev/null 2> "$tmp/hard.err"
[ $? -eq 1 ] && grep -q "is not a plain file of its own" "$tmp/hard.err" ||
  fail "hard-linked lock file: $(cat "$tmp/hard.err")"
[ "$(cat "$tmp/victim")" = "precious" ] || fail "the hard-linked lock file was written"

# Inputs named like helper files: the scene as the lock file is refused and kept; the scene
# under the old staging name is read and kept.
mkdir "$tmp/named"
cp "$scene" "$tmp/named/.r.h5.lock"
"$exe" run "$tmp/named/.r.h5.lock" --out "$tmp/named/r.h5" > /dev/null 2> "$tmp/named.err"
[ $? -eq 1 ] && grep -q "would overwrite the input" "$tmp/named.err" ||
  fail "scene named as the lock file: $(cat "$tmp/named.err")"
cmp -s "$scene" "$tmp/named/.r.h5.lock" || fail "the scene named as the lock file was changed"
mv "$tmp/named/.r.h5.lock" "$tmp/named/.r.h5.partial"
"$exe" run "$tmp/named/.r.h5.partial" --out "$tmp/named/r.h5" > /dev/null 2> "$tmp/named2.err" ||
  fail "scene named as the old staging file: $(cat "$tmp/named2.err")"
cmp -s "$scene" "$tmp/named/.r.h5.partial" || fail "the scene named as the staging file was changed"
# A lock file holding anything but a process id is not ours to truncate.
mkdir "$tmp/foreign"
echo "notes of the user" > "$tmp/foreign/.r.h5.lock"
"$exe" run "$scene" --out "$tmp/foreign/r.h5" > /dev/null 2> "$tmp/foreign.err"
[ $? -eq 1 ] && grep -q "is not a depthfem lock file" "$tmp/foreign.err" ||
  fail "foreign lock file: $(cat "$tmp/foreign.err")"
grep -q "notes of the user" "$tmp/foreign/.r.h5.lock" || fail "a foreign lock file was truncated"

# No helper file is left behind by a run that completed or one that failed.
mkdir "$tmp/clean"
"$exe" run "$scene" --out "$tmp/clean/ok.h5" > /dev/null 2>&1 || fail "clean run failed"
"$exe" run "$scene" --out "$tmp/clean/bad.h5" --set boundary.3.offset=-1.5 \
  --set solver.min_increment=0.01 > /dev/null 2>&1 && fail "the failing run succeeded"
left=$(cd "$tmp/clean" && ls -A | sort | tr '\n' ' ')
[ "$left" = "bad.h5 bad.xdmf2 bad.xmf ok.h5 ok.xdmf2 ok.xmf " ] || fail "files left: $left"

# An increment below the resolution of the load factors ends the run with a located error
# instead of writing the same step forever.
timeout 120 "$exe" run "$scene" --out "$tmp/clean/tiny.h5" --set boundary.3.offset=-1.5 \
  --set solver.min_increment=1e-13 > /dev/null 2> "$tmp/tiny.err"
rc=$?
[ $rc -eq 1 ] || fail "an increment that no longer moves the load must exit 1, got $rc"
grep -q "no longer changes the load" "$tmp/tiny.err" || fail "tiny increment: $(cat "$tmp/tiny.err")"

# File-size limits from below the first write to past the end of a small dynamic run: every
# run ends with exit 0, or exit 1 and one error line; its results file says so; its sidecars
# are valid XML listing every step it printed; every printed step is in the results file.
cat > "$tmp/drop.json" << 'JSON'
{
  "name": "drop", "analysis": "dynamic", "gravity": [0, 0, -9.81],
  "bodies": [{"name": "block", "mesh": {"generator": "box", "lo": [0,0,0.01], "hi": [0.3,0.2,0.2],
              "cells": [2,1,1]}, "material": {"model": "neo_hookean", "youngs": 1e5, "poisson": 0.3}}],
  "obstacles": [{"name": "floor", "type": "plane", "point": [0,0,0], "normal": [0,0,1], "penalty": 1e6}],
  "dynamic": {"integrator": "newmark", "time_step": 0.005, "duration": 1.5}
}
JSON
# Sixteen one-cell bodies: a sidecar that grows faster than the results file, so that the
# limit cuts a sidecar's write.
/usr/bin/python3 - > "$tmp/many.json" << 'PY'
import json
bodies = [{"name": f"b{k}", "mesh": {"generator": "box", "lo": [0.5 * k, 0, 0.01],
           "hi": [0.5 * k + 0.3, 0.2, 0.2], "cells": [1, 1, 1]},
           "material": {"model": "neo_hookean", "youngs": 1e5, "poisson": 0.3}} for k in range(16)]
print(json.dumps({"name": "many", "analysis": "dynamic", "gravity": [0, 0, -9.81], "bodies": bodies,
                  "obstacles": [{"name": "floor", "type": "plane", "point": [0, 0, 0],
                                 "normal": [0, 0, 1], "penalty": 1e6}],
                  "dynamic": {"integrator": "newmark", "time_step": 0.005, "duration": 1.6}}))
PY
mkdir "$tmp/limits"
sidecar_cut=0
check_limit() {  # SCENE KIB
  local scene=$1 kib=$2 rc
  rm -f "$tmp/limits"/*
  (ulimit -f "$kib"; exec "$exe" run "$scene" --out "$tmp/limits/r.h5" --threads 1) \
    > "$tmp/limits/log" 2> "$tmp/limits/err"
  rc=$?
  echo "$(basename "$scene") limit $kib KiB: exit $rc, $(grep -c '^step' "$tmp/limits/log") steps printed $(cut -c1-160 "$tmp/limits/err")"
  if [ $rc -ne 0 ]; then
    [ $rc -eq 1 ] && [ "$(wc -l < "$tmp/limits/err")" -eq 1 ] ||
      fail "limit $kib KiB: exit $rc, $(cat "$tmp/limits/err")"
  fi
  grep -q "XDMF sidecar" "$tmp/limits/err" && sidecar_cut=$((sidecar_cut + 1))
  grep -o '^step *[0-9]*' "$tmp/limits/log" | awk '{print $2}' > "$tmp/limits/printed"
  /usr/bin/python3 - "$tmp/limits" "$rc" << 'PY' || fail "limit $kib KiB (see above)"
import os, re, sys
import xml.etree.ElementTree as ET
import h5py
folder, rc = sys.argv[1], int(sys.argv[2])
printed = [int(s) for s in open(os.path.join(folder, "printed")).read().split()]
if not os.path.exists(os.path.join(folder, "r.h5")):
    sys.exit(1 if printed or rc == 0 else 0)  # refused before the file existed
with h5py.File(os.path.join(folder, "r.h5"), "r") as f:
    status = f["/run/status"][()].decode().rstrip("\0")
    steps = set(int(i) for i in f["/steps/index"][:])
expected = "completed" if rc == 0 else "failed"
if status != expected:
    print(f"status {status}, expected {expected}")
    sys.exit(1)
if any(s not in steps for s in printed):
    print(f"printed steps missing from the results file")
    sys.exit(1)
for name in ("r.xmf", "r.xdmf2"):
    path = os.path.join(folder, name)
    if not os.path.exists(path):
        continue  # the run failed before its sidecars were begun
    text = open(path).read()
    ET.fromstring(text)
    listed = len(re.findall(r'<Grid Name="step_', text))
    if listed < len(printed):
        print(f"{name} lists {listed} steps of {len(printed)} printed")
        sys.exit(1)
PY
  left=$(cd "$tmp/limits" && ls -A | grep -v -x -e log -e err -e printed -e r.h5 -e r.xmf -e r.xdmf2)
  [ -z "$left" ] || fail "limit $kib KiB: helper files left: $left"
}
for kib in 4 64 400 700 800 900 1000 1100 1200 1400 1800 4000; do check_limit "$tmp/drop.json" "$kib"; done
for kib in 6000 7000; do check_limit "$tmp/many.json" "$kib"; done
((sidecar_cut > 0)) || fail "no limit cut a sidecar's write"
echo "helper files: links, helper-named inputs, the increment bound and 14 file-size limits pass"
