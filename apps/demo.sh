#!/usr/bin/env bash
# The demo: the fold_slab scene (a thick slab folded flat onto itself under a rigid plate, its
# halves held apart by material-depth self-contact; 14 load steps, a few seconds), written to
# results/fold_slab.h5 (+ .xmf for ParaView), then two pictures: the slab half-way up
# (results/fold_slab_bending.png) and folded, seen from the side, over its reference shape
# (results/fold_slab.png).
set -euo pipefail
cd "$(dirname "$0")/.."
mkdir -p results
build/apps/depthfem run apps/scenes/fold_slab.json --out results/fold_slab.h5
build/apps/depthfem info results/fold_slab.h5
/usr/bin/python3 apps/tools/render.py results/fold_slab.h5 results/fold_slab_bending.png --step 6 \
  --view 15 -70
/usr/bin/python3 apps/tools/render.py results/fold_slab.h5 results/fold_slab.png --view 5 -90 \
  --reference
echo "demo: results/fold_slab.h5, results/fold_slab.xmf (ParaView), results/fold_slab.png," \
  "results/fold_slab_bending.png"
