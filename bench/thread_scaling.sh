#!/usr/bin/env bash
# Thread scaling of the linear solve (bench/results/thread_scaling_16core.md): the sag bar
# (cantilever_gravity 80x8x8, E = 1 MPa) and the 160x16x16 cantilever with the default solver
# (auto) and the direct one, at each thread count, one process per case; then the 480 k-tet
# cantilever at the ends of the range; then, if BEFORE names an older depthfem, that build on the
# sag bar and the 160x16x16 cantilever (its scene's direct solver) at the fewest and most threads.
#   bench/thread_scaling.sh OUT_DIR [THREADS ...]     (from the repository root, after building;
#                                                     default threads: 1 2 4 8 16)
# OUT_DIR gets scaling.csv (bench_scaling's rows: seconds per Newton iteration by phase),
# process.csv (wall, user and system seconds of every process) and log.txt (their output).
# BIN (environment) is the build folder (default build); RUN a command prefix for every program
# (for example a dynamic loader with --library-path, on a machine without the libraries);
# LIMIT the seconds one process may take (default 120; the case is then recorded as stopped).
set -uo pipefail
out=$1
shift
threads=("$@")
((${#threads[@]})) || threads=(1 2 4 8 16)
bin=${BIN:-build}
limit=${LIMIT:-120}
read -r -a run <<< "${RUN:-}"
mkdir -p "$out"
csv=$out/scaling.csv
echo "case,code,threads,status,wall_s,user_s,sys_s" > "$out/process.csv"
sag=(--set 'bodies.0.mesh.cells=[80,8,8]' --set bodies.0.material.youngs=1e6)
big=(--set 'bodies.0.mesh.cells=[160,16,16]')

# case code threads command...: one process, timed, output to the log
timed() {
  local name=$1 code=$2 t=$3 status times
  shift 3
  echo "== $name $code threads $t: $*" >> "$out/log.txt"
  times=$( { TIMEFORMAT='%R %U %S'; time timeout "$limit" "${run[@]}" "$@" \
             >> "$out/log.txt" 2>&1; } 2>&1 )
  status=$?
  echo "$name,$code,$t,$status,${times// /,}" | tee -a "$out/process.csv"
}
scaling() {  # case threads bench_scaling arguments...
  local name=$1 t=$2
  shift 2
  timed "$name" after "$t" "$bin/bench/bench_scaling" --threads "$t" --out "$csv" "$@"
}

for t in "${threads[@]}"; do
  scaling sag_bar_80 "$t" --scene cantilever --size 80 --solver auto \
    --set bodies.0.material.youngs=1e6
  scaling cantilever_160_auto "$t" --scene cantilever --size 160 --solver auto
  scaling cantilever_160_direct "$t" --scene cantilever --size 160 --solver direct
done
first=${threads[0]} last=${threads[-1]}
scaling cantilever_200_auto "$first" --scene cantilever --size 200 --solver auto
scaling cantilever_200_auto "$last" --scene cantilever --size 200 --solver auto
scaling cantilever_200_direct "$last" --scene cantilever --size 200 --solver direct

if [[ -n ${BEFORE:-} ]]; then
  for t in "$first" "$last"; do
    timed sag_bar_80 before "$t" "$BEFORE" run apps/scenes/cantilever_gravity.json \
      --out "$out/before.h5" --threads "$t" "${sag[@]}"
    timed cantilever_160_direct before "$t" "$BEFORE" run apps/scenes/cantilever_gravity.json \
      --out "$out/before.h5" --threads "$t" "${big[@]}"
  done
  rm -f "$out/before.h5"
fi
if command -v column > /dev/null; then column -t -s, "$out/process.csv"; else cat "$out/process.csv"; fi
