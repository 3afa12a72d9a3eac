#!/usr/bin/env bash
# Runs every shipped scene with every field written (stress and strain turned on) and opens the
# results in ParaView, headless, checking steps, blocks and fields against the HDF5 files
# (apps/tools/paraview_check.py). hertz_sphere runs on the coarse corner mesh of its penalty
# test (its shipped mesh takes minutes), knee_flexion over its first 1.5 degrees (three steps: the
# regions, node sets and rigid bodies are all there), its fine and Veronda variants not at all
# (the same layout). Writes bench/results/paraview_check.txt.
# Needs Debian's paraview, python3-paraview and xvfb; nothing else in the project does.
# Usage: bench/paraview_check.sh [BUILD_DIR]
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
for tool in pvbatch xvfb-run; do
  command -v "$tool" > /dev/null || { echo "paraview_check: $tool not found (apt-get install paraview python3-paraview xvfb)" >&2; exit 1; }
done
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
for scene in apps/scenes/*.json; do
  name=$(basename "$scene" .json)
  extra=()
  case "$name" in knee_flexion_*) continue ;; esac
  if [ "$name" = knee_flexion ]; then
    extra=(--set boundary.0.angle_deg=1.5 --set boundary.1.angle_deg=1.5
           --set solver.initial_increment=0.3333333333333333 --set solver.max_increment=0.3333333333333333)
  fi
  if [ "$name" = hertz_sphere ]; then
    extra=(--set 'bodies.0.mesh={"generator": "corner", "size": 16, "core": 0.12, "core_cells": 8, "ratio": 1.2}'
           --set boundary.2.nodes.plane.offset=16 --set solver.initial_increment=0.25)
  fi
  "$build/apps/depthfem" run "$scene" --out "$out/$name.h5" \
    --set 'output={"stress": true, "strain": true}' "${extra[@]}" > "$out/$name.log" 2>&1 \
    || { echo "paraview_check: $name failed: $(tail -n 1 "$out/$name.log")" >&2; exit 1; }
done
xvfb-run -a pvbatch apps/tools/paraview_check.py "$out"/*.h5 2>&1 | grep -v "no caching possible" |
  tee bench/results/paraview_check.txt
