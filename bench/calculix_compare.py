"""depthfem against CalculiX on the same linear tetrahedra.

    /usr/bin/python3 bench/calculix_compare.py SCENE.json WORK_DIR [--set PATH=VALUE]...
        [--threads N] [--label TEXT] [--csv OUT.csv] [--quadratic-volume]
    /usr/bin/python3 bench/calculix_compare.py --plot OUT.csv OUT.png

Runs `build/apps/depthfem run SCENE.json` (with the --set overrides), reads the mesh and the
scene as run back from its results file, writes a CalculiX deck with the same nodes, the same
tets as C3D4 elements, the same boundary conditions, gravity and material, runs `ccx` on it and
compares the last state of both: largest displacement, the nodal displacement difference
(largest and root mean square) beside the largest rounding of CalculiX's printed digits (all
relative to depthfem's largest displacement), the reaction of the condition with the largest
one, wall and CPU time of each process, and the largest |J - 1| of any tet. One CSV row per call
(appended to --csv, printed without).

What it can translate (anything else stops with one line): one deformable body; a static
analysis, or a dynamic one by Newmark's average acceleration rule with the lumped mass from rest
(CalculiX's alpha method with alpha = 0, the same rule; depthfem's lumped mass as CalculiX MASS
elements); gravity (in a dynamic analysis at full strength from t = 0 in both); boundary
conditions `fixed` and `displaced` (in a dynamic analysis linear in time in both) on `plane`,
`box` or `list` node sets; the materials below in the standard formulation. The energy of
`nearly_incompressible_mooney_rivlin` {C1, C2, kappa} is
C1 (Ibar1 - 3) + C2 (Ibar2 - 3) + kappa/2 ((J^2 - 1)/2 - ln J).
With C2 = 0 it is exactly CalculiX's ARRUDA-BOYCE potential with mu = 2 C1, D = 2 / kappa and
the locking stretch lambda_m -> infinity (the deck takes lambda_m = 1e5, where the series' next
term changes the stiffness by 6e-11 relative); with C2 != 0 the deck takes CalculiX's
MOONEY-RIVLIN (C10 = C1, C01 = C2, D1 = 2 / kappa), whose volumetric term (J - 1)^2 / D1 agrees
with depthfem's to second order in J - 1 and differs by kappa/6 |J - 1|^3 (+ O((J - 1)^4));
--quadratic-volume takes MOONEY-RIVLIN also for C2 = 0, so that the volumetric term is the only
difference. The paper's compressible `mooney_rivlin` with C2 = 0,
C1 (I1 - 3) + a (I3 - 1) - (C1 + a) ln I3, is exactly CalculiX's built-in Ciarlet law (a
material named CIARLET_EL, constants E and nu; its source, src/umat_ciarlet_el.f, takes
S = lambda/2 (I3 - 1) C^-1 + mu (I - C^-1), the derivative of
mu/2 (I1 - 3 - ln I3) + lambda/4 (I3 - 1 - ln I3)) with mu = 2 C1 and lambda = 4 a.
"""

import argparse
import csv
import os
import pathlib
import resource
import shutil
import subprocess
import sys
import time

import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent.parent / "apps" / "tools"))
from results import Results, ResultsError  # noqa: E402

DEPTHFEM = "build/apps/depthfem"
LAMBDA_M = 1e5  # Arruda-Boyce locking stretch: large enough that only its first term remains
FIELDS = ["label", "material", "nodes", "tets", "time_step", "max_u_depthfem", "max_u_ccx",
          "max_du_rel", "rms_du_rel", "print_bound_rel", "max_abs_J_minus_1",
          "reaction_depthfem", "reaction_ccx", "reaction_rel", "seconds_depthfem", "seconds_ccx",
          "cpu_depthfem", "cpu_ccx", "newton_depthfem", "newton_ccx", "increments_depthfem",
          "increments_ccx", "threads"]


class CompareError(Exception):
    """A scene this translation does not cover, or a run that failed."""


def node_set(X, spec, where):
    """The node indices of a scene's node-set selector, as depthfem selects them
    (core/node_sets.cpp)."""
    tol = spec.get("tolerance", 1e-9)
    if "plane" in spec:
        n = np.array(spec["plane"]["normal"], float)
        return np.flatnonzero(np.abs((X @ n - spec["plane"]["offset"]) / np.linalg.norm(n)) <= tol)
    if "box" in spec:
        lo, hi = np.array(spec["box"]["lo"]), np.array(spec["box"]["hi"])
        return np.flatnonzero(np.all((X >= lo - tol) & (X <= hi + tol), axis=1))
    if "list" in spec:
        return np.array(spec["list"], int)
    raise CompareError(f"{where}.nodes: only plane, box or list selectors are translated")


def material_card(material, quadratic_volume):
    """(kind, material name, card lines) of a depthfem material in CalculiX (see the module
    docstring); quadratic_volume: MOONEY-RIVLIN also for C2 = 0."""
    model = material.get("model")
    if material.get("formulation", "standard") != "standard" or "viscoelastic" in material:
        raise CompareError("bodies.0.material: only the standard, elastic formulation")
    if model == "mooney_rivlin" and material.get("C2", 0) == 0:
        if "youngs" in material:
            E, nu = material["youngs"], material["poisson"]
        else:  # small-strain moduli mu = 2 C1, lambda = 4 a (materials/mooney_rivlin.hpp)
            mu, lam = 2 * material["C1"], 4 * material["a"]
            E, nu = mu * (3 * lam + 2 * mu) / (lam + mu), lam / (2 * (lam + mu))
        # the material's name selects CalculiX's built-in Ciarlet law; its constants: E, nu
        return "ciarlet", "CIARLET_EL", ["*USER MATERIAL, CONSTANTS=2", f"{E!r}, {nu!r}"]
    if model != "nearly_incompressible_mooney_rivlin":
        raise CompareError("bodies.0.material: only nearly_incompressible_mooney_rivlin and "
                           "mooney_rivlin with C2 = 0 are translated")
    c1, c2, kappa = material["C1"], material["C2"], material["kappa"]
    if c2 == 0 and not quadratic_volume:
        return "arruda_boyce", "M", ["*HYPERELASTIC, ARRUDA-BOYCE",
                                     f"{2 * c1!r}, {LAMBDA_M!r}, {2 / kappa!r}"]
    return "mooney_rivlin", "M", ["*HYPERELASTIC, MOONEY-RIVLIN", f"{c1!r}, {c2!r}, {2 / kappa!r}"]


def step_procedure(scene):
    """The *STATIC or *DYNAMIC card of the scene's analysis."""
    analysis = scene.get("analysis", "static")
    if analysis == "static":
        # automatic increments bounded as depthfem's (first, smallest, largest load increment);
        # the step ends at full load
        solver = scene.get("solver", {})
        return ["*STATIC", f"{solver.get('initial_increment', 1.0)!r}, 1.0, "
                f"{solver.get('min_increment', 1e-3)!r}, {solver.get('max_increment', 1.0)!r}"]
    dynamic = scene.get("dynamic", {})
    newmark = dynamic.get("newmark", {})
    if (analysis != "dynamic" or dynamic.get("integrator") != "newmark"
            or newmark.get("beta", 0.25) != 0.25 or newmark.get("gamma", 0.5) != 0.5
            or dynamic.get("mass", "lumped") != "lumped" or "damping" in dynamic):
        raise CompareError("analysis: only static scenes and dynamic ones with the newmark "
                           "integrator (beta 1/4, gamma 1/2), the lumped mass and no damping "
                           "are translated (CalculiX's alpha method with alpha = 0)")
    if scene["bodies"][0].get("velocity", [0, 0, 0]) != [0, 0, 0]:
        raise CompareError("bodies.0.velocity: only a start from rest is translated")
    # fixed steps of time_step; loads at full strength from t = 0 in both codes
    return ["*DYNAMIC, DIRECT, ALPHA=0", f"{dynamic['time_step']!r}, {dynamic['duration']!r}"]


def positively_oriented(X, tets):
    """The tets with their corners ordered as C3D4 wants them: (x2-x1) x (x3-x1) . (x4-x1) > 0."""
    volume6 = volumes6(X, tets)
    if np.any(volume6 == 0):
        raise CompareError("a tet of zero volume")
    out = tets.copy()
    flip = volume6 < 0
    out[flip, 2], out[flip, 3] = tets[flip, 3], tets[flip, 2]
    return out


def write_deck(path, scene, X, tets, quadratic_volume):
    """Writes the CalculiX deck; returns (material kind, [(condition name, node indices)])."""
    procedure = step_procedure(scene)
    bodies = scene["bodies"]
    if len(bodies) != 1 or bodies[0].get("rigid", False):
        raise CompareError("bodies: exactly one deformable body is translated")
    if "contact" in scene or "obstacles" in scene:
        raise CompareError("contact, obstacles: not translated")
    kind, material, card = material_card(bodies[0]["material"], quadratic_volume)
    lines = ["*HEADING", f"depthfem scene {scene.get('name', '')} as C3D4", "*NODE, NSET=NALL"]
    lines += [f"{i + 1}, {x!r}, {y!r}, {z!r}" for i, (x, y, z) in enumerate(X)]
    lines.append("*ELEMENT, TYPE=C3D4, ELSET=EALL")
    lines += [f"{e + 1}, " + ", ".join(str(n + 1) for n in t)
              for e, t in enumerate(positively_oriented(X, tets))]
    conditions, boundary, moving = [], [], []
    for k, bc in enumerate(scene.get("boundary", [])):
        where = f"boundary.{k}"
        nodes = node_set(X, bc["nodes"], where)
        name = bc.get("name", f"bc{k}")
        nset = f"BC{k}"
        lines.append(f"*NSET, NSET={nset}")
        lines += [", ".join(str(n + 1) for n in nodes[i:i + 16]) for i in range(0, len(nodes), 16)]
        if bc["type"] == "fixed":
            boundary.append(f"{nset}, 1, 3")
        elif bc["type"] == "displaced":
            # static: with the load factor; dynamic: linearly in time (depthfem's t / duration)
            moving += [f"{nset}, {d + 1}, {d + 1}, {u!r}" for d, u in enumerate(bc["displacement"])]
        else:
            raise CompareError(f"{where}.type: only fixed and displaced are translated")
        conditions.append((name, nset, nodes))
    rho = bodies[0].get("density", 1000)
    g = np.array(scene.get("gravity", [0, 0, 0]), float)
    loaded = ["EALL"]
    if procedure[0].startswith("*DYNAMIC"):
        # depthfem's lumped mass, rho V / 4 from each tet a node is a corner of, as CalculiX MASS
        # elements (one element set per distinct value); CalculiX's own C3D4 mass matrix is
        # integrated at one point (rho V / 16 for every pair of corners), which depthfem has not
        nodal_mass = rho * corner_volumes(X, tets)
        lines.append("*ELEMENT, TYPE=MASS, ELSET=EMASS")
        lines += [f"{len(tets) + i + 1}, {i + 1}" for i in range(len(X))]
        for k, m in enumerate(np.unique(nodal_mass)):
            nodes = np.flatnonzero(nodal_mass == m)
            lines.append(f"*ELSET, ELSET=EM{k}")
            lines += [", ".join(str(len(tets) + n + 1) for n in nodes[i:i + 16])
                      for i in range(0, len(nodes), 16)]
            lines += [f"*MASS, ELSET=EM{k}", f"{m!r}"]
        loaded.append("EMASS")
        rho = 1e-30  # the tets' own mass (and weight) vanish beside the nodes'
    if procedure[0].startswith("*DYNAMIC"):
        lines += ["*AMPLITUDE, NAME=RAMP", f"0, 0, {scene['dynamic']['duration']!r}, 1"]
    lines += [f"*MATERIAL, NAME={material}", *card, "*DENSITY", f"{rho!r}",
              f"*SOLID SECTION, ELSET=EALL, MATERIAL={material}",
              "*STEP, NLGEOM, INC=100000", *procedure,
              # residual 1e-9 of the mean force, correction 1e-9 of the largest change
              "*CONTROLS, PARAMETERS=FIELD", "1e-9, 1e-9", "*BOUNDARY", *boundary]
    if moving and procedure[0].startswith("*DYNAMIC"):
        lines += ["*BOUNDARY, AMPLITUDE=RAMP", *moving]
    elif moving:
        lines += moving
    if np.linalg.norm(g) > 0:
        n = g / np.linalg.norm(g)
        lines.append("*DLOAD")
        lines += [f"{e}, GRAV, {np.linalg.norm(g)!r}, {n[0]!r}, {n[1]!r}, {n[2]!r}" for e in loaded]
    lines += ["*NODE PRINT, NSET=NALL", "U"]
    for _, nset, _ in conditions:
        lines += [f"*NODE PRINT, NSET={nset}, TOTALS=ONLY", "RF"]
    lines.append("*END STEP")
    path.write_text("\n".join(lines) + "\n")
    return kind, conditions


def read_dat(path, num_nodes, conditions):
    """The last increment's displacements (#nodes x 3) and the total reaction of each condition,
    from CalculiX's .dat file."""
    u = np.full((num_nodes, 3), np.nan)
    totals = {}
    block = None
    for line in path.read_text().splitlines():
        words = line.split()
        if not words:
            continue
        if words[0] in ("displacements", "total"):
            # " displacements (vx,vy,vz) for set NALL and time  0.1E+01"
            # " total force (fx,fy,fz) for set BC0 and time  0.1E+01"
            block = ("u" if words[0] == "displacements" else "rf", words[words.index("set") + 1])
        elif block and block[0] == "u":
            u[int(words[0]) - 1] = [float(w) for w in words[1:4]]
        elif block and block[0] == "rf":
            totals[block[1]] = np.array([float(w) for w in words[:3]])
    if np.isnan(u).any():
        raise CompareError(f"{path}: no displacements for every node")
    return u, [totals[nset] for _, nset, _ in conditions]


def print_rounding(values):
    """The largest rounding error of each value as the .dat file prints it (7 significant
    digits: half a unit in the 7th)."""
    magnitude = np.floor(np.log10(np.maximum(np.abs(values), 1e-300)))
    return 0.5 * 10.0 ** (magnitude - 6)


def read_sta(path):
    """(increments, Newton iterations) of the converged increments in CalculiX's .sta file."""
    rows = [line.split() for line in path.read_text().splitlines()[2:] if line.strip()]
    return len(rows), sum(int(r[3]) for r in rows)


def volumes6(p, tets):
    """Six times each tet's signed volume."""
    a, b, c, d = (p[tets[:, k]] for k in range(4))
    return np.einsum("ij,ij->i", np.cross(b - a, c - a), d - a)


def corner_volumes(X, tets):
    """Per node: V / 4 summed over the tets it is a corner of."""
    share = np.zeros(len(X))
    np.add.at(share, tets.ravel(), np.repeat(np.abs(volumes6(X, tets)) / 24, 4))
    return share


def body_load_on(nodes, scene, X, tets):
    """The gravity force on the given nodes: rho g V / 4 from each tet they are a corner of."""
    g = np.array(scene.get("gravity", [0, 0, 0]), float)
    return scene["bodies"][0].get("density", 1000) * g * corner_volumes(X, tets)[nodes].sum()


def largest_reaction(conditions, totals_ccx, reactions_depthfem, names, scene, X, tets):
    """(depthfem's, CalculiX's) reaction of the condition with the largest one: depthfem's row of
    that condition (the force it exerts on the body); CalculiX's total RF of its node set, which
    leaves out the body load applied at the set's own nodes, added back."""
    k = int(np.argmax([np.linalg.norm(t) for t in totals_ccx]))
    name, _, nodes = conditions[k]
    return (reactions_depthfem[names.index(name)],
            totals_ccx[k] - body_load_on(nodes, scene, X, tets))


def relative(difference, reference):
    return np.linalg.norm(difference) / max(np.linalg.norm(reference), 1e-300)


def run_timed(command, log, env=None, cwd=None):
    """Runs a program to its end; returns its (wall, CPU: user + system) seconds."""
    start, before = time.perf_counter(), resource.getrusage(resource.RUSAGE_CHILDREN)
    with open(log, "w") as out:
        status = subprocess.run(command, stdout=out, stderr=subprocess.STDOUT, env=env, cwd=cwd)
    seconds, after = time.perf_counter() - start, resource.getrusage(resource.RUSAGE_CHILDREN)
    if status.returncode != 0:
        raise CompareError(f"{command[0]} failed with status {status.returncode}; see {log}")
    return seconds, after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime


def compare(args):
    ccx = shutil.which("ccx")
    if ccx is None:
        raise CompareError("ccx not found: install CalculiX with apt-get install calculix-ccx")
    work = pathlib.Path(args.work)
    work.mkdir(parents=True, exist_ok=True)
    out = work / "depthfem.h5"
    command = [DEPTHFEM, "run", args.scene, "--out", str(out), "--threads", str(args.threads)]
    for s in args.set:
        command += ["--set", s]
    seconds_depthfem, cpu_depthfem = run_timed(command, work / "depthfem.log")
    with Results(str(out)) as r:
        scene = r.scene()
        X = r.f["mesh/X"][:]
        tets = r.f["mesh/tets"][:].astype(np.int64)
        last = r.step(-1)
        x = last["x"]
        reactions_depthfem = last["reactions"]
        names = list(r.f["run/constraint_names"].asstr()[:])
        newton = r.series("newton_iterations")
    kind, conditions = write_deck(work / "ccx.inp", scene, X, tets, args.quadratic_volume)
    threads = str(args.threads)
    env = dict(os.environ, OMP_NUM_THREADS=threads, CCX_NPROC_STIFFNESS=threads,
               CCX_NPROC_RESULTS=threads, CCX_NPROC_EQUATION_SOLVER=threads)
    seconds_ccx, cpu_ccx = run_timed([ccx, "-i", "ccx"], work / "ccx.log", env=env, cwd=work)
    u_ccx, totals_ccx = read_dat(work / "ccx.dat", len(X), conditions)
    increments, newton_ccx = read_sta(work / "ccx.sta")

    u = x - X
    max_u = np.linalg.norm(u, axis=1).max()
    du = np.linalg.norm(u - u_ccx, axis=1)
    reaction_d, reaction_c = (np.zeros(3), np.zeros(3))
    if conditions:
        reaction_d, reaction_c = largest_reaction(conditions, totals_ccx, reactions_depthfem,
                                                  names, scene, X, tets)
    row = {
        "label": args.label, "material": kind, "nodes": len(X), "tets": len(tets),
        "time_step": scene["dynamic"]["time_step"] if "dynamic" in scene else "",
        "max_u_depthfem": f"{max_u:.9g}",
        "max_u_ccx": f"{np.linalg.norm(u_ccx, axis=1).max():.9g}",
        "max_du_rel": f"{du.max() / max_u:.3e}",
        "rms_du_rel": f"{np.sqrt(np.mean(du ** 2)) / max_u:.3e}",
        "print_bound_rel": f"{np.linalg.norm(print_rounding(u_ccx), axis=1).max() / max_u:.3e}",
        "max_abs_J_minus_1": f"{np.abs(volumes6(x, tets) / volumes6(X, tets) - 1).max():.3e}",
        "reaction_depthfem": f"{np.linalg.norm(reaction_d):.9g}",
        "reaction_ccx": f"{np.linalg.norm(reaction_c):.9g}",
        "reaction_rel": f"{relative(reaction_d - reaction_c, reaction_d):.3e}",
        "seconds_depthfem": f"{seconds_depthfem:.3f}", "seconds_ccx": f"{seconds_ccx:.3f}",
        "cpu_depthfem": f"{cpu_depthfem:.3f}", "cpu_ccx": f"{cpu_ccx:.3f}",
        "newton_depthfem": int(newton.sum()), "newton_ccx": newton_ccx,
        "increments_depthfem": len(newton), "increments_ccx": increments, "threads": args.threads,
    }
    if args.csv:
        new = not pathlib.Path(args.csv).exists()
        with open(args.csv, "a", newline="") as f:
            w = csv.DictWriter(f, FIELDS)
            if new:
                w.writeheader()
            w.writerow(row)
    print(", ".join(f"{k} {v}" for k, v in row.items()))


def plot(csv_path, png_path):
    """Three panels of the displacement difference relative to the largest displacement: static
    cases against tets, the Mooney-Rivlin cards against the largest |J - 1|, the dynamic cases
    against the time step; grey crosses: the rounding of CalculiX's printed digits."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.ticker import NullFormatter, ScalarFormatter
    with open(csv_path) as f:
        rows = list(csv.DictReader(f))
    fig, axes = plt.subplots(1, 3, figsize=(13, 4.4))
    panels = [  # axis, rows, x label, x, joined by lines, title
        (axes[0], lambda r: not r["time_step"] and not r["label"].startswith("kappa"), "tets",
         lambda r: int(r["tets"]), True, "static: four meshes, and a prescribed tip (3840 tets)"),
        (axes[1], lambda r: r["material"] == "mooney_rivlin", "largest |J - 1| of a tet",
         lambda r: float(r["max_abs_J_minus_1"]), False,
         "against CalculiX's MOONEY-RIVLIN: (J-1)^2 / D1"),
        (axes[2], lambda r: bool(r["time_step"]), "time step [s]",
         lambda r: float(r["time_step"]), True, "dynamic: Newmark, lumped mass, 0.4 s"),
    ]
    for ax, keep, xlabel, x, joined, title in panels:
        sel = [r for r in rows if keep(r)]
        for label, marker in zip(dict.fromkeys(r["label"] for r in sel), "osD^v<>ph"):
            group = sorted((r for r in sel if r["label"] == label), key=x)
            ax.loglog([x(r) for r in group], [float(r["max_du_rel"]) for r in group],
                      marker + ("-" if joined else ""), mfc="none", ms=8, label=label)
        ax.loglog([x(r) for r in sel], [float(r["print_bound_rel"]) for r in sel], "x",
                  color="grey", label="rounding of the printed digits")
        ax.set_xlabel(xlabel)
        ax.set_title(title, fontsize=9)
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7, loc="center right" if ax is axes[0] else "best")
    axes[2].set_xticks(sorted({float(r["time_step"]) for r in rows if r["time_step"]}))
    axes[2].xaxis.set_major_formatter(ScalarFormatter())
    axes[2].xaxis.set_minor_formatter(NullFormatter())
    axes[0].set_ylabel("max |u_depthfem - u_CalculiX| / max |u|")
    fig.suptitle("depthfem against CalculiX 2.20 on the same C3D4 meshes", fontsize=11)
    fig.tight_layout()
    fig.savefig(png_path, dpi=110)


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("scene", nargs="?")
    p.add_argument("work", nargs="?", help="folder for both codes' files")
    p.add_argument("--set", action="append", default=[], help="depthfem --set PATH=VALUE")
    p.add_argument("--threads", type=int, default=1)
    p.add_argument("--label", default="")
    p.add_argument("--quadratic-volume", action="store_true",
                   help="CalculiX's MOONEY-RIVLIN also where C2 = 0 (isolates the volumetric term)")
    p.add_argument("--csv")
    p.add_argument("--plot", nargs=2, metavar=("CSV", "PNG"))
    args = p.parse_args()
    try:
        if args.plot:
            plot(*args.plot)
        elif args.scene and args.work:
            compare(args)
        else:
            p.error("give SCENE.json WORK_DIR, or --plot CSV PNG")
    except (CompareError, ResultsError, OSError, KeyError) as e:
        sys.exit(f"calculix_compare.py: error: {e}")


if __name__ == "__main__":
    main()
