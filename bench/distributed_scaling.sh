#!/usr/bin/env bash
# Strong and weak scaling of distributed static runs (bench/results/distributed.md), one thread a
# rank, one process (or one mpirun) per case:
#   strong_amg, strong_direct  the cantilever_gravity bar at STRONG_CELLS (default 160x16x16,
#                              245,760 tets) with `amg` (CG + GAMG) and `direct` (MUMPS; CHOLMOD
#                              on one process)
#   weak_amg                   uniaxial_block with about WEAK_TETS tets a rank (default 24,000:
#                              cells c^3 with 6 c^3 / P nearest it), `amg`
#   contact                    sliding_blocks as shipped (the replicated pair search)
#   bench/distributed_scaling.sh OUT_DIR [RANKS ...]     (from the repository root, after
#                                                        building; default ranks: 1 2)
# One rank runs the serial program (no mpirun). OUT_DIR gets runs.csv (one row a process: wall
# seconds, Newton and linear iterations, the phases' seconds on rank 0, the largest resident
# memory of any rank and their sum) and log.txt. BIN (environment) is the depthfem program
# (default build/apps/depthfem), MPIRUN the launcher with its options (default `mpirun
# --allow-run-as-root --oversubscribe -q`), TIME a GNU time (default /usr/bin/time), LIMIT the
# seconds a case may take (default 300; the row's status is then 124).
set -uo pipefail
out=$1
shift
ranks=("$@")
((${#ranks[@]})) || ranks=(1 2)
bin=${BIN:-build/apps/depthfem}
read -r -a mpirun <<< "${MPIRUN:-mpirun --allow-run-as-root --oversubscribe -q}"
gtime=${TIME:-/usr/bin/time}
limit=${LIMIT:-300}
strong_cells=${STRONG_CELLS:-[160,16,16]}
weak_tets=${WEAK_TETS:-24000}
mkdir -p "$out"
csv=$out/runs.csv
echo "case,ranks,tets,status,wall_s,newton,linear,force_stiffness_s,collision_s,linear_solve_s,max_rss_kb,sum_rss_kb" > "$csv"

# case ranks tets scene arguments...: one run, its output appended to the log, one row to the CSV
run_case() {
  local name=$1 p=$2 tets=$3 status start wall
  shift 3
  local log=$out/$name.$p.log launch=()
  ((p > 1)) && launch=("${mpirun[@]}" -n "$p")
  echo "== $name ranks $p: $*" >> "$out/log.txt"
  start=$EPOCHREALTIME
  rm -f "$out/rss.txt"  # one line a process, appended by each at its end
  timeout "$limit" "${launch[@]}" "$gtime" -a -o "$out/rss.txt" -f "%M" "$bin" run "$@" \
    --out "$out/run.h5" --threads 1 > "$log" 2>&1
  status=$?
  wall=$(awk -v a="$start" -v b="$EPOCHREALTIME" 'BEGIN { print b - a }')
  cat "$log" >> "$out/log.txt"
  touch "$out/rss.txt"
  awk -v c="$name" -v p="$p" -v t="$tets" -v s="$status" -v w="$wall" -v output="$log" '
    /^step/ { for (i = 1; i < NF; ++i) { if ($i == "newton") n += $(i + 1); if ($i == "linear") l += $(i + 1) } }
    /^  = force\/stiffness/ { f = $(NF - 2) } /^  = collision detection/ { d = $(NF - 2) }
    /^  = linear solve/ { ls = $(NF - 2) }
    FILENAME != output { sum += $1; if ($1 > mx) mx = $1; next }
    END { printf "%s,%d,%d,%d,%.2f,%d,%d,%s,%s,%s,%d,%d\n", c, p, t, s, w, n, l, f + 0, d + 0, ls + 0, mx, sum }
  ' "$log" "$out/rss.txt" | tee -a "$csv"
  rm -f "$out/run.h5" "$out/rss.txt"
}

cantilever=(apps/scenes/cantilever_gravity.json --set "bodies.0.mesh.cells=$strong_cells")
strong_tets=$(echo "$strong_cells" | tr -d '[]' | awk -F, '{print 6 * $1 * $2 * $3}')
for p in "${ranks[@]}"; do
  run_case strong_amg "$p" "$strong_tets" "${cantilever[@]}" --set solver.linear_solver=amg
  run_case strong_direct "$p" "$strong_tets" "${cantilever[@]}" --set solver.linear_solver=direct
  c=$(awk -v p="$p" -v t="$weak_tets" 'BEGIN { print int((t * p / 6) ^ (1 / 3) + 0.5) }')
  run_case weak_amg "$p" $((6 * c * c * c)) apps/scenes/uniaxial_block.json \
    --set "bodies.0.mesh.cells=[$c,$c,$c]" --set solver.linear_solver=amg
  run_case contact "$p" 4488 apps/scenes/sliding_blocks.json
done
if command -v column > /dev/null; then column -t -s, "$csv"; else cat "$csv"; fi
