#!/bin/bash
# The ladder from the paper's algorithm to depthfem's default on the knee's first DEGREES degrees
# (3 by default) in the paper's 3-degree intervals: one change per rung, each rung run
# once per ROUND, the rungs alternating (bench/results/knee_paper.md). Loading only: the settling
# steps that end a run with quasi-viscosity are left out (max_settle_steps 0, so those rungs end
# with "did not come to rest", after the timing table). Writes one CSV row per run to stdout.
#
#   bench/knee_paper_ladder.sh > bench/results/knee_paper_ladder.csv
# Environment: DEPTHFEM (build/apps/depthfem), DEGREES (3), ROUNDS (1), THREADS (1),
# LIMIT (seconds per run, 1200).
set -u
DEPTHFEM=${DEPTHFEM:-build/apps/depthfem}
DEGREES=${DEGREES:-3}
ROUNDS=${ROUNDS:-1}
THREADS=${THREADS:-1}
LIMIT=${LIMIT:-1200}
increment=$(/usr/bin/python3 -c "print(3 / $DEGREES)")
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
rungs=(
  "paper|"
  "direct solver|solver.linear_solver=direct"
  "energy line search|solver.linear_solver=direct solver.line_search=energy"
  "depthfem's Newton details|solver.linear_solver=direct solver.line_search=energy solver.line_search_start=legal solver.gradient_fallback=true solver.linearised_start=true"
  "no quasi-viscosity|solver.linear_solver=direct solver.line_search=energy solver.line_search_start=legal solver.gradient_fallback=true solver.linearised_start=true solver.quasi_viscosity=0"
  "candidate list (default)|solver.linear_solver=direct solver.line_search=energy solver.line_search_start=legal solver.gradient_fallback=true solver.linearised_start=true solver.quasi_viscosity=0 contact.list_margin=0.1"
)
echo "round,rung,name,loaded,wall_s,newton,linear,force_stiffness_s,collision_s,linear_solve_s,other_s,load_average"
for round in $(seq 1 "$ROUNDS"); do
  for k in "${!rungs[@]}"; do
    name=${rungs[$k]%%|*}
    sets=()
    for s in ${rungs[$k]#*|}; do sets+=(--set "$s"); done
    log=$out/rung$k.log
    timeout "$LIMIT" "$DEPTHFEM" run apps/scenes/knee_flexion_paper.json --out "$out/rung$k.h5" \
      --threads "$THREADS" --set boundary.0.angle_deg="$DEGREES" \
      --set boundary.1.angle_deg="$DEGREES" --set solver.initial_increment="$increment" \
      --set solver.max_increment="$increment" --set solver.max_settle_steps=0 "${sets[@]}" >"$log" 2>&1
    rm -f "$out/rung$k.h5" "$out/rung$k.xmf" "$out/rung$k.xdmf2"
    load=$(cut -d' ' -f1 /proc/loadavg)
    /usr/bin/python3 - "$log" "$round" "$k" "$name" "$load" <<'PY'
import re, sys
log, rnd, k, name, load = sys.argv[1:]
text = open(log, errors="replace").read()
steps = re.findall(r"^step +\d+ +load ([0-9.]+) +newton +(\d+) +linear +(\d+)", text, re.M)
wall = re.search(r"timing \(s, share of ([0-9.]+) s wall\)", text)
g = dict(re.findall(r"^  = (\S.*?)\s+([0-9.]+)\s+[0-9.]+ %$", text, re.M))
loaded = "yes" if steps and float(steps[-1][0]) == 1.0 else "no"
row = [rnd, k, f'"{name}"', loaded, wall.group(1) if wall else "",
       sum(int(s[1]) for s in steps), sum(int(s[2]) for s in steps)]
row += [g.get(x, "") for x in ("force/stiffness", "collision detection", "linear solve", "other")]
print(",".join(str(v) for v in row + [load]))
PY
  done
done
