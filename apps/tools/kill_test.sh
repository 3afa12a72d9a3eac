#!/usr/bin/env bash
# Crash safety of the results file: runs a small dynamic scene KILLS times, each killed with
# SIGKILL at a random moment while `depthfem info` reads the live file, and checks that every
# results file left behind is readable, that every step printed as completed is in it (and in
# its sidecars), that every step in it is bitwise equal to an uninterrupted run's, and that a run
# restarted from its last step (positions, velocities, time, Newmark's acceleration from the
# restart record) ends bitwise where the uninterrupted run ends.
# Usage: kill_test.sh PATH/TO/depthfem [KILLS]   (prints the figures; exit 1 on any failure)
set -u
exe=$1
kills=${2:-50}
here=$(cd "$(dirname "$0")" && pwd)
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

# A falling block on a floor: 3 x 2 x 2 cells, 60 Newmark steps (milliseconds each). The CG
# linear solver keeps nothing from step to step (the direct solver keeps its last factor, which a
# restart cannot have), so that a restarted run can be compared bitwise.
cat > "$tmp/scene.json" <<'JSON'
{
  "name": "kill_test", "analysis": "dynamic", "gravity": [0, 0, -9.81],
  "bodies": [{"name": "block", "mesh": {"generator": "box", "lo": [0,0,0.01], "hi": [0.3,0.2,0.2],
              "cells": [3,2,2]}, "material": {"model": "neo_hookean", "youngs": 1e5, "poisson": 0.3}}],
  "obstacles": [{"name": "floor", "type": "plane", "point": [0,0,0], "normal": [0,0,1], "penalty": 1e6}],
  "dynamic": {"integrator": "newmark", "time_step": 0.005, "duration": 0.3},
  "solver": {"linear_solver": "cg", "linear_tolerance": 1e-8}
}
JSON
start=$(date +%s%N)
"$exe" run "$tmp/scene.json" --out "$tmp/ref.h5" --threads 1 > "$tmp/ref.log" 2>&1 || { echo "FAIL: reference run: $(tail -1 "$tmp/ref.log")"; exit 1; }
full_us=$(( ($(date +%s%N) - start) / 1000 ))

readers=0 reader_failures=0
for ((k = 0; k < kills; k++)); do
  rm -f "$tmp"/run.* "$tmp"/.run.h5.*
  "$exe" run "$tmp/scene.json" --out "$tmp/run.h5" --threads 1 > "$tmp/run$k.log" 2>&1 &
  pid=$!
  delay=$(( RANDOM * 32768 + RANDOM ))
  delay=$(( delay % (full_us + 1) ))
  sleep "$(printf '%d.%06d' $((delay / 1000000)) $((delay % 1000000)))"
  if [ -f "$tmp/run.h5" ]; then  # a reader of the live file
    readers=$((readers + 1))
    "$exe" info "$tmp/run.h5" > /dev/null 2> "$tmp/reader.err" || { reader_failures=$((reader_failures + 1)); echo "live read failed: $(cat "$tmp/reader.err")"; }
  fi
  kill -9 "$pid" 2> /dev/null
  wait "$pid" 2> /dev/null
  for f in "$tmp"/run.h5 "$tmp"/run.xmf "$tmp"/run.xdmf2; do
    [ -f "$f" ] && cp "$f" "${f%.*}$k.${f##*.}"
  done
  grep -o '^step *[0-9]*' "$tmp/run$k.log" | awk '{print $2}' > "$tmp/printed$k"
done

/usr/bin/python3 - "$tmp" "$kills" "$readers" "$reader_failures" "$here" "$exe" <<'PY'
import os, re, subprocess, sys
import xml.etree.ElementTree as ET
import numpy as np
tmp, kills, readers, reader_failures, here, exe = sys.argv[1:7]
kills, readers, reader_failures = int(kills), int(readers), int(reader_failures)
sys.path.insert(0, here)
from results import Results
ref = Results(os.path.join(tmp, "ref.h5"))
corrupt = missing = unequal = no_file = printed_total = in_file = sidecar_missing = 0
restarts = restart_failures = restart_unequal = 0
for k in range(kills):
    printed = [int(s) for s in open(os.path.join(tmp, f"printed{k}")).read().split()]
    printed_total += len(printed)
    path = os.path.join(tmp, f"run{k}.h5")
    if not os.path.exists(path):
        no_file += 1
        missing += len(printed)  # a printed step without a file is lost
        continue
    try:
        with Results(path) as r:
            steps = {int(i): row for row, i in enumerate(r.index)}
            fields = {name: r.series(name) for name in ("x", "v", "load", "energy")}
            r.status, r.timing()
    except Exception as e:
        corrupt += 1
        print(f"run {k}: unreadable: {e}")
        continue
    in_file += len(steps)
    missing += sum(1 for s in printed if s not in steps)
    for index, row in steps.items():  # every step in the file, printed or not
        if any(not np.array_equal(values[row], ref.series(name)[ref.row_of(index)])
               for name, values in fields.items()):
            unequal += 1
    if steps and max(steps) < ref.index[-1]:  # restarted from its last step, the run ends as
        # the uninterrupted one, bitwise
        restarts += 1
        out = os.path.join(tmp, f"restart{k}.h5")
        done = subprocess.run([exe, "run", os.path.join(tmp, "scene.json"), "--out", out,
                               "--restart", path, "--threads", "1"], capture_output=True, text=True)
        if done.returncode != 0:
            restart_failures += 1
            print(f"run {k}: restart failed: {done.stderr.strip()}")
        else:
            with Results(out) as r:
                if any(not np.array_equal(r.series(name)[-1], ref.series(name)[-1])
                       for name in ("x", "v", "load")):
                    restart_unequal += 1
                    print(f"run {k}: the restart from step {max(steps)} ends elsewhere")
    for sidecar in (f"run{k}.xmf", f"run{k}.xdmf2"):
        # The results file is put in place before its sidecars are written: a run killed in
        # between leaves no sidecar, which is correct as long as it printed no step.
        try:
            text = open(os.path.join(tmp, sidecar)).read()
        except FileNotFoundError as e:
            if printed:
                sidecar_missing += 1
                print(f"run {k}: {sidecar}: {e}")
            continue
        try:
            ET.fromstring(text)
        except ET.ParseError as e:
            corrupt += 1
            print(f"run {k}: {sidecar}: {e}")
            continue
        if len(re.findall(r'<Grid Name="step_', text)) < len(printed):
            sidecar_missing += 1
print(f"kills {kills}, steps printed {printed_total}, steps in the files {in_file}, "
      f"runs killed before the file existed {no_file}, corrupt files {corrupt}, "
      f"printed-but-missing steps {missing}, steps differing from the uninterrupted run "
      f"{unequal}, sidecars missing a printed step {sidecar_missing}, "
      f"live reads {readers} (failed {reader_failures}), restarts from the last step in the "
      f"file {restarts} (failed {restart_failures}, ending elsewhere {restart_unequal})")
sys.exit(1 if corrupt or missing or unequal or sidecar_missing or reader_failures
         or restart_failures or restart_unequal else 0)
PY
