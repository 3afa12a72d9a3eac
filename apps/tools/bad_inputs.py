#!/usr/bin/python3
"""Runs depthfem on hand-made bad inputs and sorts what happens to each.

    /usr/bin/python3 apps/tools/bad_inputs.py DEPTHFEM [--csv OUT.csv]

Every case is one `depthfem` command on a scene, a mesh file, a results file (`info`, `run
--restart`) or a command line that is wrong in one way (the classes of
bench/results/reliability.md). Outcomes:
  clean      exit 1 (2 for command-line usage), the first line of stderr is
             "depthfem: error: ..." and names where: the scene file, the mesh file and line, the
             results file and dataset, or the option; with exit 1 that is the only line
  unlocated  an error, but the line names neither the file nor the option
  accepted   exit 0: a bad input run as if it were good (a silent wrong result)
  crash      killed by a signal or another exit status
  hang       still running after 30 s
Control cases (the base scene with a generated mesh, Gmsh and TetGen files, a tet given in the
other orientation, which the readers turn, physical groups; `info` on a valid results file and a
restart from it) must run and exit 0, so the harness cannot call
everything clean by rejecting everything. Prints a table per class;
exits 1 if any bad case is not clean or a control fails.
"""
import argparse
import csv
import json
import os
import pathlib
import subprocess
import sys
import tempfile
import time

BASE = {
    "name": "base",
    "analysis": "static",
    "bodies": [{
        "name": "block",
        "mesh": {"generator": "box", "lo": [0, 0, 0], "hi": [1, 1, 1], "cells": [2, 2, 2]},
        "material": {"model": "mooney_rivlin", "C1": 4000, "C2": 1000, "a": 20000},
    }],
    "boundary": [
        {"type": "fixed", "nodes": {"plane": {"normal": [1, 0, 0], "offset": 0}}},
        {"type": "displaced", "displacement": [0.1, 0, 0],
         "nodes": {"plane": {"normal": [1, 0, 0], "offset": 1}}},
    ],
    "solver": {"linear_solver": "direct", "initial_increment": 0.5},
}

CORNERS = [(x, y, z) for z in (0, 1) for y in (0, 1) for x in (0, 1)]  # node i+1: bits x, y, z
KUHN = [(0, 1, 3, 7), (0, 1, 5, 7), (0, 2, 3, 7), (0, 2, 6, 7), (0, 4, 5, 7), (0, 4, 6, 7)]


def positive(tet):
    """The Kuhn tet with its last two corners swapped where its volume is negative."""
    p = [CORNERS[i] for i in tet]
    a, b, c = ([p[k][j] - p[0][j] for j in range(3)] for k in (1, 2, 3))
    det = (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
           + a[2] * (b[0] * c[1] - b[1] * c[0]))
    return tet if det > 0 else (tet[0], tet[1], tet[3], tet[2])


TETS = [tuple(i + 1 for i in positive(t)) for t in KUHN]
NODES = [f"{i + 1} {x} {y} {z}" for i, (x, y, z) in enumerate(CORNERS)]
# A small tet on nodes 9..12 of its own: inside the cube (sharing no face with its tets), and one
# through the cube's top face.
INSIDE = NODES + [f"{9 + k} {x} {y} {z}" for k, (x, y, z) in enumerate(
    [(0.7, 0.45, 0.2), (0.8, 0.45, 0.2), (0.7, 0.55, 0.2), (0.7, 0.45, 0.3)])]
STICKING_OUT = NODES + [f"{9 + k} {x} {y} {z}" for k, (x, y, z) in enumerate(
    [(0.4, 0.4, 0.8), (0.6, 0.4, 0.8), (0.5, 0.6, 0.8), (0.5, 0.5, 1.3)])]
EXTRA = (9, 10, 11, 12)


def msh(nodes=None, tets=None, header="2.2 0 8", node_count=None, elem_count=None, tail=True,
        names=(), triangles=()):
    """A Gmsh 2.2 unit cube (8 nodes, 6 tets in the physical volume 1) with the given parts
    replaced, $PhysicalNames entries ("dim tag \"name\"") and triangles (physical tag, nodes)."""
    nodes = NODES if nodes is None else nodes
    tets = TETS if tets is None else tets
    lines = ["$MeshFormat", header, "$EndMeshFormat"]
    if names:
        lines += ["$PhysicalNames", str(len(names)), *names, "$EndPhysicalNames"]
    count = len(tets) + len(triangles)
    lines += ["$Nodes", str(len(nodes) if node_count is None else node_count), *nodes, "$EndNodes",
              "$Elements", str(count if elem_count is None else elem_count)]
    lines += [f"{k + 1} 4 2 1 1 " + " ".join(map(str, t)) for k, t in enumerate(tets)]
    lines += [f"{len(tets) + k + 1} 2 2 {tag} 1 " + " ".join(map(str, t))
              for k, (tag, *t) in enumerate(triangles)]
    if tail:
        lines.append("$EndElements")
    return "\n".join(lines) + "\n"


def tetgen(nodes=None, tets=None):
    nodes = NODES if nodes is None else nodes
    tets = TETS if tets is None else tets
    node = f"{len(nodes)} 3 0 0\n" + "\n".join(nodes) + "\n"
    ele = f"{len(tets)} 4 0\n" + "\n".join(
        f"{k + 1} " + " ".join(map(str, t)) for k, t in enumerate(tets)) + "\n"
    return node, ele


def scene(edit=None, mesh_file=None):
    s = json.loads(json.dumps(BASE))
    if mesh_file:
        s["bodies"][0]["mesh"] = {"file": mesh_file}
    if edit:
        edit(s)
    return json.dumps(s, indent=1)


def parent(s, path):
    """The object holding the last key of the path (a list of keys and indices)."""
    for key in path[:-1]:
        s = s[key]
    return s


def setter(path, value):
    """An edit that sets the key path to value."""
    def edit(s):
        parent(s, path)[path[-1]] = value
    return edit


def removal(path):
    """An edit that removes the key path."""
    def edit(s):
        del parent(s, path)[path[-1]]
    return edit


def dynamic_scene(duration):
    """The base block viscoelastic, pulled by Newmark steps of 0.01 s for `duration` s: its
    results file has velocities and a restart record (acceleration, viscoelastic history)."""
    def edit(s):
        s["analysis"] = "dynamic"
        s["bodies"][0]["material"] = {
            "model": "neo_hookean", "youngs": 1e5, "poisson": 0.3,
            "viscoelastic": {"relaxation_times": [0.01], "weights": [0.3]}}
        s["dynamic"] = {"integrator": "newmark", "time_step": 0.01, "duration": duration}
    return scene(edit)


def results_files(exe):
    """Valid results files (bytes) of runs of the base scene, of a scene with as many nodes and
    tets but another mesh (a box twice as high), and of the dynamic scene over 0.02 s."""
    out = {}
    with tempfile.TemporaryDirectory() as tmp:
        for name, text in [("base", scene()),
                           ("other", scene(setter(["bodies", 0, "mesh", "hi"], [1, 1, 2]))),
                           ("dynamic", dynamic_scene(0.02))]:
            pathlib.Path(tmp, name + ".json").write_text(text)
            subprocess.run([exe, "run", name + ".json", "--out", name + ".h5"], cwd=tmp,
                           check=True, capture_output=True, timeout=60)
            out[name] = pathlib.Path(tmp, name + ".h5").read_bytes()
    return out


def altered(results, edit):
    """The bytes of a results file after edit(h5py.File) has changed it."""
    import h5py
    with tempfile.TemporaryDirectory() as tmp:
        path = pathlib.Path(tmp, "r.h5")
        path.write_bytes(results)
        with h5py.File(path, "r+") as f:
            edit(f)
        return path.read_bytes()


def replaced(name, **dataset):
    """An edit that replaces dataset `name` by h5py's create_dataset(name, **dataset)."""
    def edit(f):
        del f[name]
        f.create_dataset(name, **dataset)
    return edit


def flipped(results, offset):
    """The bytes of a results file with every bit of byte `offset` flipped."""
    b = bytearray(results)
    b[offset] ^= 0xff
    return bytes(b)


def data_offset(results, dataset):
    """Where the data of a contiguous dataset of a results file begin."""
    import h5py
    with tempfile.TemporaryDirectory() as tmp:
        path = pathlib.Path(tmp, "r.h5")
        path.write_bytes(results)
        with h5py.File(path, "r") as f:
            return f[dataset].id.get_offset()


def cases(exe):
    """(class, name, files {name: text or bytes}, arguments after 'depthfem', where-tokens (a
    tuple: all of its tokens), control)."""
    run = ["run", "scene.json", "--out", "out.h5"]
    where = ["scene.json"]
    out = []

    def add(cls, name, files, args=None, names=None, control=False):
        out.append((cls, name, files, args or run, names or where, control))

    # Controls.
    add("control", "base scene, generated mesh", {"scene.json": scene()}, control=True)
    add("control", "base scene, Gmsh file", {"scene.json": scene(mesh_file="m.msh"),
                                             "m.msh": msh()}, control=True)
    node, ele = tetgen()
    add("control", "a tet in the other orientation (reoriented)",
        {"scene.json": scene(mesh_file="m.msh"),
         "m.msh": msh(tets=[(TETS[0][0], TETS[0][1], TETS[0][3], TETS[0][2])] + TETS[1:])},
        control=True)
    add("control", "Gmsh file with a named surface and volume",
        {"scene.json": scene(mesh_file="m.msh"),
         "m.msh": msh(names=['2 2 "bottom"', '3 1 "cube"'], triangles=[(2, 1, 2, 4)])},
        control=True)
    add("control", "base scene, TetGen files", {"scene.json": scene(mesh_file="m.ele"),
                                                "m.node": node, "m.ele": ele}, control=True)

    # Sizes and counts.
    cells = ["bodies", 0, "mesh", "cells"]
    for name, value in [("zero cells", [0, 2, 2]), ("negative cells", [-1, 2, 2]),
                        ("cells 2^32+40", [2**32 + 40, 1, 1]), ("cells 2^63", [2**63, 1, 1]),
                        ("cell product overflows int", [100000, 100000, 100000]),
                        ("cells beyond memory", [3000, 3000, 3000]),
                        ("fractional cells", [1.5, 2, 2]), ("cells as strings", ["2", 2, 2]),
                        ("two cell counts", [2, 2]), ("cells null", None)]:
        add("sizes and counts", name, {"scene.json": scene(setter(cells, value))})
    solver = ["solver"]
    for key, value in [("max_newton_iterations", 2**32 + 1), ("max_newton_iterations", 0),
                       ("max_newton_iterations", -1), ("initial_increment", 0),
                       ("initial_increment", -0.5), ("initial_increment", 2),
                       ("min_increment", -1), ("tolerance", -1), ("tolerance", 1e308),
                       ("tolerance", 0), ("linear_max_iterations", -5),
                       ("linear_tolerance", 0), ("forcing_max", 1),
                       ("auto_flops_per_entry", 0)]:
        add("sizes and counts", f"solver.{key} {value}",
            {"scene.json": scene(setter(solver + [key], value))})
    for key, value in [("preset", "papr"), ("preset", 1), ("preset", ""),
                       ("gmres_restart", 0), ("gmres_restart", 2**31),
                       ("line_search_start", "half"), ("gradient_fallback", "yes"),
                       ("linearised_start", 1), ("direct_precision", "half"),
                       ("direct_precision", 32)]:
        add("solver preset and its keys", f"solver.{key} {value!r}",
            {"scene.json": scene(setter(solver + [key], value))})
    for duration, step in [(1000, 1e-9), (1, 0), (1, -0.01), (-1, 0.01), (0, 0.01)]:
        def dynamic(s, duration=duration, step=step):
            s["analysis"] = "dynamic"
            s["dynamic"] = {"integrator": "implicit_euler", "time_step": step,
                            "duration": duration}
        add("sizes and counts", f"dynamic duration {duration} step {step}",
            {"scene.json": scene(dynamic)})
    for name, section in [
            ("generalized_alpha rho_inf 1.5",
             {"integrator": "generalized_alpha", "generalized_alpha": {"rho_inf": 1.5}}),
            ("generalized_alpha rho_inf -0.1",
             {"integrator": "generalized_alpha", "generalized_alpha": {"rho_inf": -0.1}}),
            ("generalized_alpha section with newmark",
             {"integrator": "newmark", "generalized_alpha": {"rho_inf": 0.5}}),
            ("arkode_dirk order 6", {"integrator": "arkode_dirk", "arkode": {"order": 6}}),
            ("arkode_dirk consistent mass", {"integrator": "arkode_dirk", "mass": "consistent"}),
            ("arkode fixed_step as a number", {"integrator": "arkode_dirk",
                                               "arkode": {"fixed_step": 1}}),
            ("cvode_bdf max_order 6", {"integrator": "cvode_bdf", "cvode": {"max_order": 6}}),
            ("cvode_bdf max_order 0", {"integrator": "cvode_bdf", "cvode": {"max_order": 0}}),
            ("cvode_bdf max_order 2.5", {"integrator": "cvode_bdf", "cvode": {"max_order": 2.5}}),
            ("cvode_bdf relative_tolerance 0",
             {"integrator": "cvode_bdf", "cvode": {"relative_tolerance": 0}}),
            ("cvode_bdf absolute_tolerance -1",
             {"integrator": "cvode_bdf", "cvode": {"absolute_tolerance": -1}}),
            ("cvode_bdf max_steps 0", {"integrator": "cvode_bdf", "cvode": {"max_steps": 0}}),
            ("cvode_bdf fixed_step", {"integrator": "cvode_bdf", "cvode": {"fixed_step": True}}),
            ("cvode section with arkode_dirk", {"integrator": "arkode_dirk",
                                                "cvode": {"max_order": 2}}),
            ("cvode_bdf consistent mass", {"integrator": "cvode_bdf", "mass": "consistent"})]:
        def dynamic(s, section=section):
            s["analysis"] = "dynamic"
            s["dynamic"] = {"time_step": 0.01, "duration": 0.02, **section}
        add("sizes and counts", f"dynamic {name}", {"scene.json": scene(dynamic)})
    for every in [0, -3, 2**32 + 1, 1.5]:
        def output(s, every=every):
            s["output"] = {"every": every}
        add("sizes and counts", f"output.every {every}", {"scene.json": scene(output)})

    # Materials and numbers that make the arithmetic non-finite.
    material = ["bodies", 0, "material"]
    nh = lambda e, nu: setter(material, {"model": "neo_hookean", "youngs": e, "poisson": nu})
    for name, edit in [("youngs 1e300", nh(1e300, 0.3)), ("youngs 1e308", nh(1e308, 0.3)),
                       ("youngs 0", nh(0, 0.3)), ("youngs negative", nh(-1e6, 0.3)),
                       ("poisson 0.5", nh(1e6, 0.5)), ("poisson -1", nh(1e6, -1)),
                       ("poisson 0.7", nh(1e6, 0.7)), ("youngs 1e-320", nh(1e-320, 0.3)),
                       ("C1 negative", setter(material + ["C1"], -4000)),
                       ("a making the bulk modulus negative", setter(material + ["a"], -1e5)),
                       ("a 1e400 (infinite)", setter(material + ["a"], 1e400)),
                       ("density negative", setter(["bodies", 0, "density"], -1)),
                       ("density 1e309", setter(["bodies", 0, "density"], 1e309)),
                       ("unknown model", setter(material + ["model"], "rubber")),
                       ("unknown formulation", setter(material + ["formulation"], "mixed")),
                       ("formulation not a string", setter(material + ["formulation"], 1)),
                       ("poisson 0.5 with nodal pressure",
                        lambda s: (nh(1e6, 0.5)(s), setter(material + ["formulation"],
                                                           "nodal_pressure")(s))),
                       ("patch size 0",
                        lambda s: (setter(material + ["formulation"], "patch_volume")(s),
                                   setter(material + ["patch_size"], 0)(s))),
                       ("patch size 2.5",
                        lambda s: (setter(material + ["formulation"], "patch_volume")(s),
                                   setter(material + ["patch_size"], 2.5)(s))),
                       ("patch size without the patch-volume formulation",
                        setter(material + ["patch_size"], 6)),
                       ("box hi = lo", setter(["bodies", 0, "mesh", "hi"], [0, 0, 0])),
                       ("box hi below lo", setter(["bodies", 0, "mesh", "hi"], [-1, 1, 1])),
                       ("gravity infinite", setter(["gravity"], [0, 0, 1e400])),
                       ("displacement 1e300", setter(["boundary", 1, "displacement"],
                                                     [1e300, 0, 0]))]:
        add("non-finite arithmetic and bad numbers", name, {"scene.json": scene(edit)})
    viscoelastic = material + ["viscoelastic"]
    ve = lambda times, weights: setter(viscoelastic,
                                       {"relaxation_times": times, "weights": weights})
    for name, edit in [("relaxation time negative", ve([0.1, -1], [0.2, 0.3])),
                       ("relaxation time zero", ve([0], [0.2])),
                       ("relaxation time 1e400", ve([1e400], [0.2])),
                       ("Prony weight zero", ve([0.1], [0])),
                       ("Prony weight negative", ve([0.1], [-0.2])),
                       ("Prony weights summing to 1", ve([0.1, 1], [0.6, 0.4])),
                       ("Prony weights summing to more than 1", ve([0.1, 1], [0.7, 0.9])),
                       ("more weights than times", ve([0.1], [0.2, 0.3])),
                       ("no relaxation times", ve([], [])),
                       ("unknown static modulus",
                        setter(viscoelastic, {"relaxation_times": [1], "weights": [0.5],
                                              "static_modulus": "relaxed"})),
                       ("viscoelastic with nodal pressure",
                        lambda s: (ve([1], [0.5])(s), setter(material + ["formulation"],
                                                             "nodal_pressure")(s)))]:
        add("non-finite arithmetic and bad numbers", name, {"scene.json": scene(edit)})

    # JSON.
    valid = scene()
    for name, text in [("empty file", ""), ("truncated", valid[:len(valid) // 2]),
                       ("trailing comma", valid.replace('"static",', '"static",,')),
                       ("top level an array", "[" + valid + "]"),
                       ("100,000 levels of nesting",
                        valid[:-1] + ', "x": ' + "[" * 100000 + "]" * 100000 + "}"),
                       ("65 levels of nesting",
                        valid[:-1] + ', "x": ' + "[" * 65 + "]" * 65 + "}"),
                       ("20 MiB of whitespace", valid + " " * (20 << 20)),
                       ("duplicate key", valid.replace('"name": "base",',
                                                       '"name": "base", "name": "again",')),
                       ("binary garbage", "\x00\xff\xfe{" * 100),
                       ("control character in a key", valid.replace('"name": "base"',
                                                                    '"na\\u0001me": "base"')),
                       ("unknown key", valid.replace('"name": "base"',
                                                     '"name": "base", "gravty": [0, 0, -9.8]')),
                       ("number where a string goes", valid.replace('"static"', "7")),
                       ("no bodies", scene(removal(["bodies"]))),
                       ("empty bodies", scene(setter(["bodies"], []))),
                       ("unterminated string", valid.replace('"base"', '"base')),
                       ("comment", "// a scene\n" + valid)]:
        add("JSON", name, {"scene.json": text})

    # Boundary conditions and node sets.
    for name, edit in [("plane matching no node",
                        setter(["boundary", 0, "nodes", "plane", "offset"], 7)),
                       ("unknown node set", setter(["boundary", 0, "nodes"], {"set": "nope"})),
                       ("unknown body", setter(["boundary", 0, "nodes"], {"body": "nope"})),
                       ("node list out of range", setter(["boundary", 0, "nodes"],
                                                         {"list": [0, 1, 99999]})),
                       ("node list 2^40", setter(["boundary", 0, "nodes"], {"list": [2**40]})),
                       ("zero normal", setter(["boundary", 0, "nodes", "plane", "normal"],
                                              [0, 0, 0])),
                       ("unknown boundary type", setter(["boundary", 0, "type"], "glued")),
                       ("contradictory planes", setter(["boundary"], BASE["boundary"][:1] + [
                           {"type": "plane", "normal": [1, 0, 0], "offset": offset,
                            "nodes": {"plane": {"normal": [1, 0, 0], "offset": 1}}}
                           for offset in (0.1, 0.2)])),
                       ("nothing held under gravity", lambda s: s.update(
                           boundary=[], gravity=[0, 0, -9.81])),
                       ("negative penalty", setter(["contact"], {"model": "material_depth",
                                                                 "penalty": -1})),
                       ("unknown excluded interface", setter(["contact"], {
                           "model": "material_depth", "penalty": 1e6, "exclude": ["bar/floor"]})),
                       ("negative list margin", setter(["contact"], {
                           "model": "material_depth", "penalty": 1e6, "list_margin": -0.1}))]:
        add("boundary and contact", name, {"scene.json": scene(edit)})

    # Mesh files: Gmsh.
    gm = lambda text: {"scene.json": scene(mesh_file="m.msh"), "m.msh": text}
    mesh_where = ["m.msh"]
    bad_node = lambda k, line: [line if i == k else n for i, n in enumerate(NODES)]
    for name, text in [
            ("empty file", ""),
            ("unknown version", msh(header="9.9 0 8")),
            ("binary format", msh(header="2.2 1 8")),
            ("node section ends early", msh(node_count=9)),
            ("element section cut off", msh(tail=False)),
            ("negative node count", msh(node_count=-3)),
            ("node count 2^40", msh(node_count=2**40)),
            ("element count 2^40", msh(elem_count=2**40)),
            ("coordinate not a number", msh(nodes=bad_node(2, "3 0 one 0"))),
            ("coordinate nan", msh(nodes=bad_node(2, "3 nan 1 0"))),
            ("coordinate inf", msh(nodes=bad_node(2, "3 inf 1 0"))),
            ("coordinate 1e400", msh(nodes=bad_node(2, "3 1e400 1 0"))),
            ("node number repeated", msh(nodes=bad_node(2, "2 0 1 0"))),
            ("tet names node 0", msh(tets=[(0, 2, 4, 8)] + TETS[1:])),
            ("tet names a missing node", msh(tets=[(1, 2, 4, 99)] + TETS[1:])),
            ("tet listed twice", msh(tets=TETS + [TETS[0]])),
            ("tet with a repeated node", msh(tets=[(1, 2, 2, 8)] + TETS[1:])),
            ("flat tet (zero volume)", msh(tets=TETS + [(1, 2, 3, 4)])),
            ("overlapping tets (a face in three)", msh(tets=TETS + [(1, 2, 4, 6)])),
            ("tet inside others, sharing no face", msh(nodes=INSIDE, tets=TETS + [EXTRA])),
            ("tet sticking out of the others", msh(nodes=STICKING_OUT, tets=TETS + [EXTRA])),
            ("corner tet of the cube's own nodes", msh(tets=TETS + [(1, 2, 3, 5)])),
            ("surface and volume of the same name",
             msh(names=['2 2 "cube"', '3 1 "cube"'], triangles=[(2, 1, 2, 4)])),
            ("unnamed surface and volume of the same tag", msh(triangles=[(1, 1, 2, 4)])),
            ("names the results file stores as one ('/' is '_')",
             msh(names=['2 2 "a/b"', '3 1 "a_b"'], triangles=[(2, 1, 2, 4)])),
            ("node in no tet", msh(nodes=NODES + ["9 5 5 5"])),
            ("no tets", msh(tets=[])),
            ("three-node tet line", msh().replace("4 2 1 1 " + " ".join(map(str, TETS[0])),
                                                  "4 2 1 1 1 2 3")),
    ]:
        add("mesh files: Gmsh", name, gm(text), names=mesh_where)
    # TetGen.
    tg_where = ["m.node", "m.ele"]
    for name, (node, ele) in [
            ("node count too large", (f"{99} 3 0 0\n" + "\n".join(NODES) + "\n",
                                      tetgen()[1])),
            ("element names a missing node", tetgen(tets=[(1, 2, 4, 99)] + TETS[1:])),
            ("tet listed twice", tetgen(tets=TETS + [TETS[0]])),
            ("flat tet", tetgen(tets=TETS + [(1, 2, 3, 4)])),
            ("tet inside others, sharing no face", tetgen(nodes=INSIDE, tets=TETS + [EXTRA])),
            ("tet sticking out of the others", tetgen(nodes=STICKING_OUT, tets=TETS + [EXTRA])),
            ("coordinate not a number", tetgen(nodes=bad_node(0, "1 x 0 0"))),
            ("node in no tet", tetgen(nodes=NODES + ["9 5 5 5"])),
            ("ele empty", (tetgen()[0], "")),
    ]:
        add("mesh files: TetGen", name, {"scene.json": scene(mesh_file="m.ele"),
                                         "m.node": node, "m.ele": ele}, names=tg_where)
    def second_body(s):
        s["bodies"].append({"name": "other", "mesh": {"file": "b.msh", "translate": [3, 0, 0]},
                            "material": BASE["bodies"][0]["material"]})
    add("mesh files: other", "two meshes' node sets stored as one ('a/b', 'a_b')",
        {"scene.json": scene(second_body, mesh_file="a.msh"),
         "a.msh": msh(names=['2 2 "a/b"', '3 1 "cube"'], triangles=[(2, 1, 2, 4)]),
         "b.msh": msh(names=['2 2 "a_b"', '3 1 "cube"'], triangles=[(2, 1, 2, 4)])},
        names=["b.msh"])
    for name, text, names in [
            ("OBJ surface given as a mesh", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", ["m.obj"]),
            ("missing mesh file", None, ["m.msh"]),
            ("unknown extension", "x", ["m.vtk"])]:
        file = names[0]
        files = {"scene.json": scene(mesh_file=file)}
        if text is not None:
            files[file] = text
        add("mesh files: other", name, files, names=names)

    # The command line.
    ok = {"scene.json": scene(), "m.msh": msh()}
    for name, args, names in [
            ("--out is the scene", ["run", "scene.json", "--out", "scene.json"], where),
            ("--out is the mesh", ["run", "scene_file.json", "--out", "m.msh"], ["m.msh"]),
            ("--out in a missing folder", ["run", "scene.json", "--out", "no/dir/out.h5"],
             ["no/dir/out.h5"]),
            ("missing scene file", ["run", "nothing.json", "--out", "out.h5"], ["nothing.json"]),
            ("scene is a folder", ["run", ".", "--out", "out.h5"], ["."]),
            ("no --out", ["run", "scene.json"], ["--out"]),
            ("--threads 0", run + ["--threads", "0"], ["--threads"]),
            ("--threads 2^40", run + ["--threads", str(2**40)], ["--threads"]),
            ("--threads word", run + ["--threads", "many"], ["--threads"]),
            ("--set without =", run + ["--set", "solver.tolerance"], ["--set"]),
            ("--set unknown path", run + ["--set", "solver.toleranse=1"], ["solver.toleranse"]),
            ("--set bad JSON value", run + ["--set", "solver.tolerance=[1,"], ["--set"]),
            ("--set index out of range", run + ["--set", "bodies.7.density=1"], ["bodies"]),
            ("unknown option", run + ["--fast"], ["--fast"]),
            ("unknown command", ["fly", "scene.json"], ["fly"]),
            ("--step without --restart", run + ["--step", "3"], ["--step"]),
            ("--restart from a missing file", run + ["--restart", "gone.h5"], ["gone.h5"]),
            ("--restart from a non-HDF5 file", run + ["--restart", "m.msh"], ["m.msh"]),
            ("info on a missing file", ["info", "gone.h5"], ["gone.h5"]),
            ("info on a non-HDF5 file", ["info", "m.msh"], ["m.msh"]),
    ]:
        files = dict(ok)
        if "scene_file.json" in args:
            files["scene_file.json"] = scene(mesh_file="m.msh")
        add("command line", name, files, args=args, names=names)

    # Results files read by `info` and `run --restart`: the error names the file and the dataset.
    h5 = results_files(exe)
    restart = run + ["--restart", "r.h5", "--step", "1"]
    add("control", "info on a valid results file", {"r.h5": h5["base"]}, args=["info", "r.h5"],
        control=True)
    add("control", "restart from a valid results file", {"scene.json": scene(), "r.h5": h5["base"]},
        args=restart, control=True)
    nan = float("nan")
    both, restart_only = ("info", "run --restart"), ("run --restart",)  # info reads no index or x
    for name, results, dataset, commands in [
            ("flipped superblock byte", flipped(h5["base"], 40), "HDF5", both),
            # A string: length (4 bytes), heap collection address (8), object index (4).
            ("damaged heap index of a string of /mesh/body_names",
             flipped(h5["base"], data_offset(h5["base"], "/mesh/body_names") + 13),
             "/mesh/body_names", both),
            ("/steps/load of shape (N, 0)",
             altered(h5["base"], replaced("/steps/load", shape=(2, 0), dtype="f8")), "/steps/load",
             both),
            ("NaN in /steps/index",
             altered(h5["base"], replaced("/steps/index", data=[0.0, nan])), "/steps/index", both),
            ("1e300 in /steps/index",
             altered(h5["base"], replaced("/steps/index", data=[0.0, 1e300])), "/steps/index",
             both),
            ("2^40 in /steps/index (int64)",
             altered(h5["base"], replaced("/steps/index", data=[0, 2**40], dtype="i8")),
             "/steps/index", restart_only),
            ("scalar /mesh/X", altered(h5["base"], replaced("/mesh/X", data=1.0)), "/mesh/X", both),
            ("empty /run/status",
             altered(h5["base"], replaced("/run/status", shape=(0,), dtype="S16")), "/run/status",
             both),
            ("NaN position in /steps/x", altered(h5["base"], lambda f: f["/steps/x"].__setitem__(
                (1, 3, 1), nan)), "/steps/x", restart_only),
            ("/run attribute threads an array",
             altered(h5["base"], lambda f: f["/run"].attrs.__setitem__("threads", [2] * 1000)),
             "threads", both),
            ("results of another scene with as many nodes and tets", h5["other"], "/mesh/X",
             restart_only)]:
        files = {"scene.json": scene(), "r.h5": results}
        for command in commands:
            args = ["info", "r.h5"] if command == "info" else restart
            add("results files", f"{command}: {name}", files, args=args,
                names=[("r.h5", dataset)])
    # A time-dependent restart (the dynamic scene run on to 0.04 s) also reads the velocities and
    # the restart record.
    dynamic = {"scene.json": dynamic_scene(0.04)}
    restart = run + ["--restart", "r.h5"]
    add("control", "dynamic restart from a valid results file", {**dynamic, "r.h5": h5["dynamic"]},
        args=restart, control=True)
    for name, edit, dataset in [
            ("NaN velocity in /steps/v", lambda f: f["/steps/v"].__setitem__((1, 3, 1), nan),
             "/steps/v"),
            ("2.5 in /restart/step", replaced("/restart/step", data=[2.5, 1.0]), "/restart/step"),
            ("/restart/step of 3 slots", replaced("/restart/step", data=[0, 1, -1], dtype="i4"),
             "/restart/step"),
            ("NaN in /restart/acceleration",
             lambda f: f["/restart/acceleration"].__setitem__((1, 2, 0), nan),
             "/restart/acceleration"),
            ("/restart/history of another width",
             replaced("/restart/history", shape=(2, 8, 12), dtype="f8"), "/restart/history"),
            ("infinite /restart/history",
             lambda f: f["/restart/history"].__setitem__((1, 0, 0), float("inf")),
             "/restart/history")]:
        add("results files", f"dynamic run --restart: {name}",
            {**dynamic, "r.h5": altered(h5["dynamic"], edit)}, args=restart,
            names=[("r.h5", dataset)])
    add("results files", "dynamic run --restart: a static run's file",
        {**dynamic, "r.h5": h5["base"]}, args=restart, names=[("r.h5", "analysis")])
    return out


def classify(rc, err, names, timed_out):
    lines = err.splitlines()
    if timed_out:
        return "hang"
    if rc == 0:
        return "accepted"
    if rc not in (1, 2) or "Sanitizer" in err:
        return "crash"
    first = lines[0] if lines else ""
    if not first.startswith("depthfem: error: ") or (rc == 1 and len(lines) != 1):
        return "unlocated"
    return ("clean" if any(all(t in first for t in (n if isinstance(n, tuple) else (n,)))
                           for n in names) else "unlocated")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("depthfem")
    parser.add_argument("--csv", help="one row per case")
    args = parser.parse_args()
    exe = str(pathlib.Path(args.depthfem).resolve())
    rows = []
    for cls, name, files, argv, names, control in cases(exe):
        with tempfile.TemporaryDirectory() as tmp:
            for file, text in files.items():
                pathlib.Path(tmp, file).write_bytes(
                    text if isinstance(text, bytes) else text.encode("utf-8", "surrogateescape"))
            before = {f: pathlib.Path(tmp, f).read_bytes() for f in files}
            start = time.monotonic()
            try:
                p = subprocess.run([exe, *argv], cwd=tmp, capture_output=True, timeout=30,
                                   env={**os.environ, "OMP_NUM_THREADS": "1"})
                rc, err, timed_out = p.returncode, p.stderr.decode(errors="replace"), False
            except subprocess.TimeoutExpired as e:
                rc, err, timed_out = None, (e.stderr or b"").decode(errors="replace"), True
            seconds = time.monotonic() - start
            outcome = classify(rc, err, names, timed_out)
            changed = [f for f in files if pathlib.Path(tmp, f).read_bytes() != before[f]]
        if control:
            outcome = "control ok" if rc == 0 else "control FAILED"
        elif changed:
            outcome = "input overwritten"
        first = err.splitlines()[0] if err.splitlines() else ""
        rows.append({"class": cls, "case": name, "outcome": outcome, "exit": rc,
                     "seconds": f"{seconds:.2f}", "message": first})
    if args.csv:
        with open(args.csv, "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=list(rows[0]))
            w.writeheader()
            w.writerows(rows)
    outcomes = ["clean", "unlocated", "accepted", "crash", "hang", "input overwritten"]
    print("| class | cases | " + " | ".join(outcomes) + " |")
    print("|---" * (len(outcomes) + 2) + "|")
    classes = list(dict.fromkeys(r["class"] for r in rows if r["class"] != "control"))
    for cls in classes + ["all"]:
        sel = [r for r in rows if r["class"] != "control" and cls in ("all", r["class"])]
        counts = [sum(r["outcome"] == o for r in sel) for o in outcomes]
        print(f"| {cls} | {len(sel)} | " + " | ".join(map(str, counts)) + " |")
    bad = [r for r in rows if r["outcome"] not in ("clean", "control ok")]
    for r in bad:
        print(f"{r['outcome']}: {r['class']}: {r['case']} (exit {r['exit']}): {r['message']}")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
