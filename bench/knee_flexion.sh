#!/usr/bin/env bash
# Scene benchmark of the paper's knee (section 6): runs a knee-flexion scene and writes its
# figures to bench/results/ (rerun it after a change to the solver or the kernels to compare):
#   knee_flexion[_TAG]_steps.csv   per step: angle, Newton iterations, seconds, penetration, area
#   knee_flexion[_TAG]_timing.csv  the breakdown beside the paper's (seconds, share of the wall)
#   knee_flexion[_TAG].md          the same as Markdown tables, with total wall time, Newton
#                                  iterations per step and the speed-up over the paper's 376 min
#   knee_flexion[_TAG].log         the run's own output
# Usage (from the repository root, after building):
#   bench/knee_flexion.sh [SCENE.json [TAG [depthfem options...]]]
#   bench/knee_flexion.sh                                  # apps/scenes/knee_flexion.json
#   bench/knee_flexion.sh apps/scenes/knee_flexion_fine.json fine
# KNEE_RESULTS=PATH.h5 keeps the results file there (for the figures, or a --restart from it);
# without it the run writes into a temporary folder, removed at the end.
set -euo pipefail
scene=${1:-apps/scenes/knee_flexion.json}
tag=${2:+_$2}
shift $(($# < 2 ? $# : 2))
out=bench/results/knee_flexion$tag
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
h5=${KNEE_RESULTS:-$tmp/run.h5}
status=0
build/apps/depthfem run "$scene" --out "$h5" "$@" > "$out.log" 2>&1 || status=$?
sed -i "s|$h5|RUN.h5|g" "$out.log"  # the log names no path of this machine
/usr/bin/python3 bench/knee_report.py "$h5" "$out.log" "$out"
exit $status
