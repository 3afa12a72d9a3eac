#!/usr/bin/env bash
# Distributed runs (mpirun -n 2 and 3, as root and oversubscribed as on CI's two cores) against
# the serial run: the positions at every step both completed agree within a stated fraction of
# the largest displacement. The differences come from the Newton tolerance alone (the converged
# residual forces differ: MUMPS solves where the serial run factors a shifted matrix), so each
# case states the tolerance its Newton tolerance allows:
# - static uniaxial_block, sliding_blocks (contact) and fold_slab (self-contact; its indefinite
#   systems solved shifted on both), Newton tolerance 1e-12, 1e-9 and 1e-9 x E h^2 per dof: 1e-6
#   (measured 8e-16, 6e-9 and 6e-10);
# - dynamic and quasistatic scenes, with the Newton tolerance set to 1e-12 x E h^2 per dof: 1e-6
#   (measured 1e-13 for falling_bars with Newmark and 4e-11 for bars_drop; at the scenes' own 1e-9
#   falling_bars differs by 1.2e-7, a thousandfold, as the residuals do);
# - hertz_sphere, coarsened (979 nodes), at its own Newton tolerance 1e-9: converged residual
#   forces up to 1.6e-2 N on a block of E = 100 kPa move a node by about F / (E a) = 4e-6 m
#   (a = 0.0375 m, the cells at the contact), 4e-3 of the 1 mm displacement of the first
#   increment: 5e-3 (measured 2.8e-4).
# A run that fails on every rank ends with one error line and keeps its completed steps.
# Usage: test_distributed.sh PATH/TO/depthfem SOURCE_DIR
source "$(dirname "$0")/preamble.sh"
mpi() { mpirun --allow-run-as-root --oversubscribe -q -n "$@"; }

# against_serial RANKS NAME TOLERANCE SCENE [ARGUMENTS...]: a serial run of SCENE with the
# arguments (once per NAME) and one on RANKS ranks agree within TOLERANCE at every step; only
# rank 0 printed; /run records the rank count.
against_serial() {
  local ranks=$1 name=$2 tolerance=$3 scene=$4
  shift 4
  local run=("$exe" run "$src/apps/scenes/$scene.json" "$@" --out)
  [ -f "$tmp/$name.h5" ] || "${run[@]}" "$tmp/$name.h5" > /dev/null 2>&1 || fail "serial $name exited $?"
  mpi "$ranks" "${run[@]}" "$tmp/${name}_$ranks.h5" > "$tmp/$name.log" 2>&1 \
    || fail "mpirun -n $ranks $name exited $?: $(tail -3 "$tmp/$name.log")"
  [ "$(grep -c "^scene $scene" "$tmp/$name.log")" -eq 1 ] || fail "$name: more than one rank printed"
  /usr/bin/python3 "$src/apps/tools/compare_runs.py" "$tmp/$name.h5" "$tmp/${name}_$ranks.h5" \
    --tolerance "$tolerance" > "$tmp/$name.cmp" || fail "$name on $ranks ranks: $(tail -2 "$tmp/$name.cmp")"
  /usr/bin/python3 -c "import h5py,sys; sys.exit(int(h5py.File(sys.argv[1])['run'].attrs['ranks'] != int(sys.argv[2])))" \
    "$tmp/${name}_$ranks.h5" "$ranks" || fail "$name: /run ranks is not $ranks"
}

against_serial 2 uniaxial_block 1e-6 uniaxial_block
against_serial 3 uniaxial_block 1e-6 uniaxial_block
against_serial 2 sliding_blocks 1e-6 sliding_blocks
# MUMPS' factor kept as DirectSolver keeps CHOLMOD's: CG on it solves some Newton systems (126
# solves, 64 factorisations measured; 123 and 123 with every matrix factored), within the
# agreement above.
/usr/bin/python3 - "$tmp/sliding_blocks_2.h5" <<'PY' || fail "sliding_blocks: the factor was never kept"
import sys, h5py
s = h5py.File(sys.argv[1])["steps"]
factored, solves = s["factorizations"][:].sum(), s["linear_solves"][:].sum()
sys.exit(0 if 0 < factored < solves else f"{factored} factorisations in {solves} solves")
PY
against_serial 2 fold_slab 1e-6 fold_slab
# auto applies the serial rule to the whole first matrix, its pattern gathered from the ranks'
# parts: uniaxial_block's predicted flops per entry are 28.4 for the whole matrix, 15.6 and 22.4
# for the two ranks' parts (measured), so a crossover of 25 takes AMG-CG (no factorisation) as
# the serial run does, where a rule applied to the parts would take MUMPS; 1e12 takes MUMPS.
for crossover in 25 1e12; do
  against_serial 2 "auto_$crossover" 1e-6 uniaxial_block --set solver.linear_solver='"auto"' \
    --set solver.auto_flops_per_entry=$crossover
  /usr/bin/python3 - "$tmp/auto_$crossover.h5" "$tmp/auto_${crossover}_2.h5" "$crossover" <<'PY' \
    || fail "auto with crossover $crossover chose differently"
import sys, h5py
direct = float(sys.argv[3]) > 28.4
for f in sys.argv[1:3]:
    factored = h5py.File(f)["steps"]["factorizations"][:].sum()
    if (factored > 0) != direct:
        sys.exit(f"{f}: {factored} factorisations, expected {'some' if direct else 'none'}")
PY
done

# Time-dependent analyses (Newton tolerance 1e-12 x E h^2 per dof, see above). Newmark and
# generalized-alpha with mass and stiffness (Rayleigh) damping: inertia, dashpots and gravity.
tight=(--set solver.tolerance=1e-12)
bars=(--set dynamic.duration=0.2 --set dynamic.time_step=0.02 "${tight[@]}"
      --set 'dynamic.damping={"mass": 0.5, "stiffness": 0.002}')
against_serial 2 newmark 1e-6 falling_bars "${bars[@]}" --set dynamic.integrator=newmark
against_serial 3 alpha 1e-6 falling_bars "${bars[@]}" --set dynamic.integrator=generalized_alpha
# The reported energies (elastic and gravity, the tethers' parts left out) and kinetic energies
# agree as the positions do (first order in their difference).
/usr/bin/python3 - "$tmp/newmark.h5" "$tmp/newmark_2.h5" <<'PY' || fail "newmark: the energies differ"
import sys, h5py, numpy as np
a, b = (h5py.File(f)["steps"] for f in sys.argv[1:])
for key in ("energy", "kinetic_energy"):
    if np.abs(a[key][:] - b[key][:]).max() > 1e-6 * np.abs(a[key][:]).max():
        sys.exit(f"{key}: {a[key][:]} against {b[key][:]}")
PY
# Quasistatic viscous flow (the node dashpots).
against_serial 2 quasistatic 1e-6 falling_bars "${tight[@]}" --set analysis=quasistatic \
  --set 'dynamic={"time_step": 0.05, "duration": 0.5, "viscosity": 2000}'
# Implicit Euler with material-depth contact between the bars, self-contact on,
# and the floor: the bars land at t = 0.1 s and press each other (2 mm deep) by 0.2 s.
against_serial 2 bars_drop 1e-6 bars_drop "${tight[@]}" --set dynamic.duration=0.25 \
  --set dynamic.time_step=0.01 --set contact.self_contact=true
# Its contact report, merged from each rank's shares (the pairs of its own tets): the interface
# rows and the surface fields agree as the positions do (measured 3.4e-10 of the largest force,
# 7.7e-10 of the largest traction, 1.1e-9 of the largest contact area).
/usr/bin/python3 - "$tmp/bars_drop.h5" "$tmp/bars_drop_2.h5" <<'PY' || fail "bars_drop: the contact report differs"
import sys, h5py, numpy as np
a, b = (h5py.File(f)["steps"] for f in sys.argv[1:])
for key in ("contact_forces", "contact_force_magnitudes", "contact_areas", "contact_traction",
            "contact_pressure", "contact_gap", "contact_fraction"):
    x, y = a[key][:], b[key][:]
    if x.shape != y.shape or np.abs(x - y).max() > 1e-6 * np.abs(x).max():
        sys.exit(f"{key}: {np.abs(x - y).max()} apart, largest {np.abs(x).max()}")
PY
# Static contact with an obstacle, at the scene's own Newton tolerance (see above).
against_serial 2 hertz_sphere 5e-3 hertz_sphere --set bodies.0.mesh.core_cells=4 \
  --set bodies.0.mesh.ratio=1.5

# Viscoelastic bars (implicit Euler): each rank keeps the history of its own tets; the viscous
# stress, the restart record's history and the dissipated energy in the file are summed over
# the ranks (measured 4e-13, 1.3e-13 and 2e-14 of their largest values apart from the serial
# run's: 1e-9). A run restarted on 2 ranks from a 2-rank file's record goes on as the serial run
# (measured 4e-16 of the positions: 1e-6 of the largest displacement, as above).
visco=(falling_bars_viscoelastic "${tight[@]}")
against_serial 2 viscoelastic 1e-6 "${visco[@]}" --set dynamic.duration=0.2
mpi 2 "$exe" run "$src/apps/scenes/${visco[0]}.json" "${visco[@]:1}" --set dynamic.duration=0.1 \
  --out "$tmp/visco_half.h5" > /dev/null 2>&1 || fail "viscoelastic to 0.1 s on 2 ranks exited $?"
mpi 2 "$exe" run "$src/apps/scenes/${visco[0]}.json" "${visco[@]:1}" --set dynamic.duration=0.2 \
  --restart "$tmp/visco_half.h5" --step 9 --out "$tmp/visco_restart.h5" > /dev/null 2>&1 \
  || fail "viscoelastic restarted on 2 ranks exited $?"
/usr/bin/python3 - "$tmp/viscoelastic.h5" "$tmp/viscoelastic_2.h5" "$tmp/visco_restart.h5" <<'PY' \
  || fail "viscoelastic: the history fields differ"
import sys, h5py, numpy as np
serial, ranks, restarted = (h5py.File(f) for f in sys.argv[1:])
def close(a, b, what, tolerance):
    if a.shape != b.shape or np.abs(a - b).max() > tolerance * np.abs(a).max():
        sys.exit(f"{what}: {np.abs(a - b).max()} apart, largest {np.abs(a).max()}")
for key in ("viscous_stress", "dissipated_energy"):
    close(serial["steps"][key][:], ranks["steps"][key][:], key, 1e-9)
close(serial["restart/history"][:], ranks["restart/history"][:], "restart/history", 1e-9)
u = serial["steps/x"][-1] - serial["mesh/X"][:]
close(u, restarted["steps/x"][-1] - serial["mesh/X"][:], "restarted positions", 1e-6)
close(serial["steps/viscous_stress"][-1], restarted["steps/viscous_stress"][-1], "restarted stress", 1e-9)
PY

# A solve that fails on every rank: one line, exit 1, the completed steps kept by rank 0.
source "$src/tests/apps/failed_run.sh"
check_failed_run mpi 2

# Bad input, met by every rank before they start: one line, exit 1.
mpi 2 "$exe" run "$src/apps/scenes/uniaxial_block.json" --out "$tmp/in.h5" --set solver.min_increment=-1 \
  > /dev/null 2> "$tmp/in.log"
rc=$?
[ $rc -eq 1 ] || fail "bad input exited $rc, expected 1"
[ "$(wc -l < "$tmp/in.log")" -eq 1 ] || fail "expected one error line, got: $(cat "$tmp/in.log")"

# The explicit and SUNDIALS integrators: every rank advances the replicated state with the
# gradient summed over the ranks (arkode_dirk's and cvode_bdf's implicit solves are the
# distributed Newton solve), so the ranks agree bit for bit and take the same adaptive steps; the
# serial run's gradient sums in another order, and its adaptive steps may differ by a few
# (ERK: 1948 internal steps serial, 1926 on 2 ranks). Measured 8e-12 (symplectic Euler, 500 steps),
# 8e-10 (arkode ERK) and 5e-12 (cvode_bdf, 3 ranks) of the largest displacement; 1e-6 allowed.
against_serial 2 symplectic 1e-6 falling_bars --set dynamic.integrator=symplectic_euler \
  --set dynamic.duration=0.05 --set dynamic.time_step=0.0001
plain=(--set dynamic.duration=0.2 --set dynamic.time_step=0.02 "${tight[@]}")
against_serial 2 erk 1e-6 falling_bars "${plain[@]}" --set dynamic.integrator=arkode
against_serial 3 bdf 1e-6 falling_bars "${plain[@]}" --set dynamic.integrator=cvode_bdf
echo "distributed: all checks passed"
