#!/usr/bin/env bash
# The scaling study of the linear solvers (bench/results/scaling.md): cantilever_gravity (bending)
# and sliding_blocks (material-depth contact) at five sizes from about 20 k to 1.07 M tets, with
# each solver, one process per case (bench_scaling appends one CSV row each).
#   bench/scaling.sh [OUT.csv] [SOLVER ...]     (from the repository root, after building;
#                                               default solvers: auto direct amg)
# A case that runs past LIMIT seconds (environment, default 1800) is recorded with success -1.
# CANTILEVER and SLIDING (environment) replace the sizes of a scene ("" leaves the scene out);
# THREADS (environment) is passed as --threads (default 0: every core).
set -euo pipefail
out=${1:-bench/results/scaling.csv}
shift || true
solvers=("$@")
((${#solvers[@]})) || solvers=(auto direct amg)
limit=${LIMIT:-1800}
threads=${THREADS:-0}
declare -A sizes=([cantilever]="${CANTILEVER-70 100 140 200 260}"
                  [sliding]="${SLIDING-1.6 2.4 3.4 4.6 6.2}")
for scene in cantilever sliding; do
  for size in ${sizes[$scene]}; do
    for solver in "${solvers[@]}"; do
      status=0
      timeout "$limit" build/bench/bench_scaling --scene "$scene" --size "$size" \
        --solver "$solver" --threads "$threads" --out "$out" || status=$?
      if ((status == 124)); then
        echo "$scene,$size,,,$solver,$threads,-1,,,,$limit,,,,," >> "$out"
        echo "$scene $size $solver: stopped after $limit s"
      fi
    done
  done
done
