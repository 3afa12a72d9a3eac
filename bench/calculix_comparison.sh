#!/usr/bin/env bash
# depthfem against CalculiX (ccx, Debian's calculix-ccx) on the same linear tets (C3D4): the
# cantilever of apps/scenes/cantilever_gravity.json made soft enough to sag 8 to 23 % of its
# length (shear modulus 2 MPa, bulk modulus about 10 mu) at four meshes, the same bar bent by a
# prescribed tip displacement, and both in Newmark dynamics; each case by
# bench/calculix_compare.py (one process per code, one thread each). One CSV row per case
# (bench/results/calculix.md reads them), then the figure.
#   bench/calculix_comparison.sh [OUT_DIR]   (from the repository root after building depthfem;
#   OUT_DIR defaults to bench/results; MESHES="[20,2,2] [40,4,4] [80,8,8]" and
#   FINE="[160,16,16]" by default)
# Cases (label in the CSV):
#   sag_neo_hookean   C1 = 1 MPa, C2 = 0, kappa = 20 MPa: the same energy as CalculiX's
#                     ARRUDA-BOYCE with lambda_m -> infinity; MESHES, then FINE
#   sag_mooney_rivlin C1 = 0.7 MPa, C2 = 0.3 MPa, kappa = 20 MPa against CalculiX's MOONEY-RIVLIN
#                     (volumetric term (J-1)^2 / D1: differs from depthfem's at third order); MESHES
#   sag_paper_mooney_rivlin  the paper's compressible mooney_rivlin, C1 = 1 MPa, C2 = 0,
#                     a = 4.5 MPa (nu = 0.45): exactly CalculiX's built-in Ciarlet law; MESHES
#   sag_neo_hookean_quadratic_volume  the first against CalculiX's MOONEY-RIVLIN with C01 = 0:
#                     only the volumetric terms differ; MESHES
#   kappa_mooney_rivlin  sag_mooney_rivlin at [40,4,4] with kappa = 10, 100, 1000 mu
#   tip_neo_hookean, tip_mooney_rivlin, tip_paper_mooney_rivlin  no gravity, the end x = 1
#                     moved by 0.3 m down, [40,4,4]
#   dyn_tip_neo_hookean  dynamic (Newmark, lumped mass), no gravity, the end moved down 0.3 m
#                     linearly over 0.4 s, from rest, [20,2,2], time steps 0.01 and 0.005 s
#   dyn_sag_neo_hookean  dynamic, gravity at full strength from t = 0, 0.4 s, [20,2,2], time
#                     steps 0.02 to 0.0025 s
set -euo pipefail
out=${1:-bench/results}
meshes=${MESHES:-"[20,2,2] [40,4,4] [80,8,8]"}
fine=${FINE-"[160,16,16]"}
fail() { echo "calculix_comparison.sh: $*" >&2; exit 1; }
command -v ccx > /dev/null || fail "ccx not found (apt-get install calculix-ccx)"
[ -x build/apps/depthfem ] || fail "build/apps/depthfem not built"
mkdir -p "$out"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
csv=$out/calculix.csv
rm -f "$csv"
scene=apps/scenes/cantilever_gravity.json
neo='bodies.0.material={"model":"nearly_incompressible_mooney_rivlin","C1":1e6,"C2":0,"kappa":2e7}'
paper='bodies.0.material={"model":"mooney_rivlin","C1":1e6,"C2":0,"a":4.5e6}'
nim='bodies.0.material={"model":"nearly_incompressible_mooney_rivlin"'
mr() { echo "$nim,\"C1\":7e5,\"C2\":3e5,\"kappa\":$1}"; }  # kappa = $1
tip='boundary=[{"name":"clamp","type":"fixed","nodes":{"plane":{"normal":[1,0,0],"offset":0}}},
  {"name":"tip","type":"displaced","displacement":[0,0,-0.3],
   "nodes":{"plane":{"normal":[1,0,0],"offset":1}}}]'
compare() { /usr/bin/python3 bench/calculix_compare.py "$scene" "$tmp/run" --csv "$csv" "$@"; }

for cells in $meshes; do
  compare --label sag_neo_hookean --set "$neo" --set "bodies.0.mesh.cells=$cells"
  compare --label sag_mooney_rivlin --set "$(mr 2e7)" --set "bodies.0.mesh.cells=$cells"
  compare --label sag_paper_mooney_rivlin --set "$paper" --set "bodies.0.mesh.cells=$cells"
  compare --label sag_neo_hookean_quadratic_volume --set "$neo" --set "bodies.0.mesh.cells=$cells" \
    --quadratic-volume
done
for cells in $fine; do
  compare --label sag_neo_hookean --set "$neo" --set "bodies.0.mesh.cells=$cells"
done
for kappa in 2e7 2e8 2e9; do
  compare --label kappa_mooney_rivlin --set "$(mr $kappa)" --set "bodies.0.mesh.cells=[40,4,4]"
done
compare --label tip_neo_hookean --set "$neo" --set "gravity=[0,0,0]" --set "$tip" \
  --set "bodies.0.mesh.cells=[40,4,4]"
compare --label tip_mooney_rivlin --set "$(mr 2e7)" --set "gravity=[0,0,0]" --set "$tip" \
  --set "bodies.0.mesh.cells=[40,4,4]"
compare --label tip_paper_mooney_rivlin --set "$paper" --set "gravity=[0,0,0]" --set "$tip" \
  --set "bodies.0.mesh.cells=[40,4,4]"
dynamic() { echo "dynamic={\"integrator\":\"newmark\",\"time_step\":$1,\"duration\":0.4}"; }
for h in 0.01 0.005; do
  compare --label dyn_tip_neo_hookean --set "$neo" --set "gravity=[0,0,0]" --set "$tip" \
    --set "bodies.0.mesh.cells=[20,2,2]" --set analysis=dynamic --set "$(dynamic $h)"
done
for h in 0.02 0.01 0.005 0.0025; do
  compare --label dyn_sag_neo_hookean --set "$neo" --set "bodies.0.mesh.cells=[20,2,2]" \
    --set analysis=dynamic --set "$(dynamic $h)"
done
/usr/bin/python3 bench/calculix_compare.py --plot "$csv" "$out/calculix.png"
cat "$csv"
