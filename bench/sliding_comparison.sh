#!/usr/bin/env bash
# Scene benchmark for the paper's central claim: the sliding_blocks scene with the material-depth
# contact and with the node-to-surface baseline. Writes one CSV row per model: completed steps,
# final load factor, Newton iterations per step (mean, max), steps whose increment had to be cut,
# and wall time.
#   bench/sliding_comparison.sh [OUT.csv]      (run from the repository root after building)
set -euo pipefail
out=${1:-bench/results/sliding_comparison.csv}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
echo "contact_model,status,completed_steps,final_load,newton_mean,newton_max,cut_steps,seconds" > "$out"
for model in material_depth node_to_surface; do
  start=$(date +%s.%N)
  build/apps/depthfem run apps/scenes/sliding_blocks.json --out "$tmp/$model.h5" --set contact.model=$model \
    > "$tmp/$model.log" 2>&1 || true
  seconds=$(echo "$(date +%s.%N) - $start" | bc)
  /usr/bin/python3 - "$tmp/$model.h5" "$model" "$seconds" >> "$out" <<'PY'
import sys
import numpy as np
sys.path.insert(0, "apps/tools")
from results import Results
path, model, seconds = sys.argv[1], sys.argv[2], float(sys.argv[3])
with Results(path) as r:
    loads, newton, status = r.series("load"), r.series("newton_iterations"), r.status
increments = np.diff(np.concatenate([[0.0], loads]))
print(f"{model},{status},{len(loads)},{loads[-1]:.4f},{newton.mean():.2f},{newton.max()},"
      f"{int((increments < 0.02 - 1e-9).sum())},{seconds:.1f}")
PY
done
cat "$out"
