#!/usr/bin/env bash
# The linear-solve targets (bench/results/targets.md), before against after: the
# sag bar (cantilever_gravity 80x8x8, E = 1 MPa) and the 160x16x16 cantilever, run alternately
# by an older build and this one at 1 and 2 threads, twice; wall and CPU seconds of each process.
#   bench/targets_before_after.sh BEFORE_DEPTHFEM [OUT.csv]    (from the repository root)
# BEFORE_DEPTHFEM: the depthfem executable of the older code; this build runs the 160x16x16
# cantilever with the default linear solver (auto), the older one with the scene's (direct).
set -euo pipefail
before=$1
out=${2:-bench/results/targets_before_after.csv}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
echo "case,code,threads,rep,newton_iterations,wall_s,cpu_s" > "$out"
run() {  # case code threads rep overrides...
  local name=$1 code=$2 threads=$3 rep=$4 bin=build/apps/depthfem
  shift 4
  [[ $code == before ]] && bin=$before
  /usr/bin/time -f "%e %U %S" -o "$tmp/time" "$bin" run apps/scenes/cantilever_gravity.json \
    --out "$tmp/run.h5" --threads "$threads" "$@" > "$tmp/log"
  local newton
  newton=$(awk '/^step/ {for (i = 1; i < NF; ++i) if ($i == "newton") s += $(i + 1)} END {print s}' "$tmp/log")
  awk -v p="$name,$code,$threads,$rep,$newton" '{print p "," $1 "," $2 + $3}' "$tmp/time" | tee -a "$out"
}
for rep in 1 2; do
  for threads in 1 2; do
    run sag_bar_80 before "$threads" "$rep" --set 'bodies.0.mesh.cells=[80,8,8]' \
      --set bodies.0.material.youngs=1e6
    run sag_bar_80 after "$threads" "$rep" --set 'bodies.0.mesh.cells=[80,8,8]' \
      --set bodies.0.material.youngs=1e6
  done
done
for rep in 1 2; do
  for threads in 1 2; do
    run cantilever_160 before "$threads" "$rep" --set 'bodies.0.mesh.cells=[160,16,16]'
    run cantilever_160 after "$threads" "$rep" --set 'bodies.0.mesh.cells=[160,16,16]' \
      --set solver.linear_solver=auto
  done
done
