#!/usr/bin/env bash
# Cost of the nodal-pressure and patch-volume formulations against the standard tet on one mesh:
# the cantilever (apps/scenes/cantilever_gravity.json) at CELLS, one thread, E = 100 MPa, as the
# standard tet at nu = 0.3 and at nu = 0.4999 (which locks), the nodal-pressure tet and the
# patch-volume tet (patches of 6 tets: the hexahedra) at nu = 0.4999, run alternately ROUNDS
# times, the load average (uptime) before each round. One CSV row per run: Newton iterations, tip deflection, seconds in
# force/stiffness and in the linear solve (the results file's timing), and both per Newton iteration.
#   bench/nearly_incompressible.sh [OUT.csv]   (from the repository root after building;
#   CELLS=[80,8,8] ROUNDS=3 by default)
set -euo pipefail
out=${1:-bench/results/nearly_incompressible_cost.csv}
cells=${CELLS:-[80,8,8]}
rounds=${ROUNDS:-3}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
echo "round,formulation,poisson,newton,tip_z,force_stiffness_s,linear_solve_s,force_per_newton_s,solve_per_newton_s" > "$out"
for round in $(seq 1 "$rounds"); do
  uptime >&2
  for case in standard:0.3 standard:0.4999 nodal_pressure:0.4999 patch_volume:0.4999; do
    formulation=${case%%:*} poisson=${case##*:}
    build/apps/depthfem run apps/scenes/cantilever_gravity.json --out "$tmp/run.h5" --threads 1 \
      --set "bodies.0.mesh.cells=$cells" --set "bodies.0.material.poisson=$poisson" \
      --set "bodies.0.material.formulation=$formulation" > /dev/null
    /usr/bin/python3 - "$tmp/run.h5" "$round" "$formulation" "$poisson" >> "$out" <<'PY'
import sys
sys.path.insert(0, "apps/tools")
from results import Results
path, round_, formulation, poisson = sys.argv[1:]
with Results(path) as r:
    newton = int(r.series("newton_iterations").sum())
    tip = float(r.step(-1)["displacement"][:, 2].min())
    timing = r.timing()
force = sum(s for name, s in timing.items() if name.startswith("force/stiffness"))
solve = sum(s for name, s in timing.items() if name.startswith("linear solve"))
print(f"{round_},{formulation},{poisson},{newton},{tip:.6g},{force:.3f},{solve:.3f},"
      f"{force / newton:.4f},{solve / newton:.4f}")
PY
  done
done
cat "$out"
