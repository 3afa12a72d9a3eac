"""Open depthfem results in ParaView, headless, and check what ParaView shows against the HDF5 file.

    xvfb-run -a pvbatch apps/tools/paraview_check.py RESULT.h5 [RESULT.h5 ...]

Needs Debian's paraview, python3-paraview and xvfb (not needed by the build or the tests). For
each results file and each of ParaView's XDMF readers, opening the sidecar written for it
(XDMF Reader: RESULT.xdmf2; Xdmf3 Reader T and Xdmf3 Reader S, which shows the blocks as
unnamed pieces: RESULT.xmf), it checks that:
  * the time steps are 0 (the reference state) and then every step's load, exactly (the settling
    steps of a static run, all at load 1, at 2, 3, ...);
  * the blocks are the bodies, named "body (material)", a body with several element regions
    replaced by one block per region, named "body/region (material)", with the body's points and
    the region's cells, and "boundary"; each with exactly the expected point, cell and
    field-data arrays;
  * at the reference state, a middle step and the last step, the points, the connectivity and
    every array equal the HDF5 datasets (ParaView reads the same doubles; the displacement equals
    x - X), the boundary's field data equals the step's values, and six-component arrays are
    named XX, YY, ZZ, XY, YZ, XZ.
Prints a summary of each file and one verdict per reader; exits with status 1 if a check fails.
"""

import os
import re
import sys

import numpy as np
from paraview import servermanager
from paraview.simple import Delete, Xdmf3ReaderS, Xdmf3ReaderT, XDMFReader
from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkCommonDataModel import vtkCompositeDataSet

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from results import Results as ResultsReader  # noqa: E402

READERS = {
    "XDMF Reader": lambda path: XDMFReader(FileNames=[path]),
    "Xdmf3 Reader T": lambda path: Xdmf3ReaderT(FileName=path),
    "Xdmf3 Reader S": lambda path: Xdmf3ReaderS(FileName=path),
}
NAMED = {"XDMF Reader": True, "Xdmf3 Reader T": True, "Xdmf3 Reader S": False}
# The sidecar each reader opens: the readers take different notations for a part of a dataset.
SIDECAR = {"XDMF Reader": ".xdmf2", "Xdmf3 Reader T": ".xmf", "Xdmf3 Reader S": ".xmf"}
# Per-step datasets by the array name ParaView shows.
NODE_FIELDS = {"displacement": "displacement", "velocity": "v"}
TET_FIELDS = ("stress", "von_mises", "strain", "volume_ratio")
TRIANGLE_FIELDS = ("contact_pressure", "contact_traction", "contact_gap", "contact_fraction")
TENSOR_COMPONENTS = ["XX", "YY", "ZZ", "XY", "YZ", "XZ"]


class CheckFailed(Exception):
    """A difference between what ParaView shows and the HDF5 file."""


def expect(condition, what):
    if not condition:
        raise CheckFailed(what)


def expect_equal(shown, stored, what):
    """Exact equality of an array ParaView shows with the stored one (same shape, same doubles)."""
    shown, stored = np.asarray(shown), np.asarray(stored)
    expect(shown.shape == stored.shape, f"{what}: shape {shown.shape}, stored {stored.shape}")
    expect(np.array_equal(shown, stored), f"{what}: values differ from the HDF5 file "
           f"(largest difference {np.abs(shown - stored).max():.3g})")


class Results:
    """What the HDF5 file says the sidecar must show."""

    def __init__(self, results):
        self.results = results
        self.f = h5 = results.f
        mesh = h5["mesh"]
        self.X = mesh["X"][:]
        self.tets = mesh["tets"][:]
        self.tris = mesh["tris"][:]
        self.tet_body = mesh["tet_body"][:]
        tet_region = mesh["tet_region"][:]
        names = list(mesh["body_names"].asstr()[:])
        materials = list(mesh["body_materials"].asstr()[:])
        region_names = list(mesh["region_names"].asstr()[:])
        region_materials = list(mesh["region_materials"].asstr()[:])
        self.blocks = []  # (block name, node range, tet range)
        for b, name in enumerate(names):
            tets = np.flatnonzero(self.tet_body == b)
            used = self.tets[tets]
            nodes = range(used.min(), used.max() + 1)
            regions = [r for r in dict.fromkeys(tet_region[tets]) if r >= 0]  # in order
            if len(regions) < 2:
                self.blocks.append((f"{name} ({materials[b]})", nodes,
                                    range(tets[0], tets[-1] + 1)))
                continue
            for r in regions:
                here = np.flatnonzero(tet_region == r)
                self.blocks.append((f"{name}/{region_names[r]} ({region_materials[r]})", nodes,
                                    range(here[0], here[-1] + 1)))
        self.depth = mesh["depth"][:] if "depth" in mesh else None
        # The sidecar's times: the loads, then 2, 3, ... for the settling steps of a static run.
        self.times = [0.0]
        for load, settling in zip(results.series("load"), results.series("settling")):
            settled = sum(1 for t in self.times if t > 1)
            self.times.append(2.0 + settled if settling else float(load))
        self.node_fields = [n for n, d in NODE_FIELDS.items() if results.has(d)]
        self.tet_fields = [n for n in TET_FIELDS if results.has(n)]
        self.triangle_fields = [n for n in TRIANGLE_FIELDS if results.has(n)]
        self.constraints = list(h5["run/constraint_names"].asstr()[:])
        self.contacts = list(h5["run/contact_names"].asstr()[:])

    def group(self, state):
        """The datasets of state `state` (0: the reference state)."""
        return self.results.reference() if state == 0 else self.results.step(state - 1)

    def node_field(self, g, field):
        """A node field of state group g; the displacement as x - X, from the positions."""
        return g["x"][()] - self.X if field == "displacement" else g[NODE_FIELDS[field]][()]

    def field_data(self, state):
        """The boundary's field data at a step: name -> values."""
        if state == 0:
            return {}
        g = self.group(state)
        values = {"step": [g["index"]], "load": [g["load"]], "settling": [g["settling"]],
                  "newton_iterations": [g["newton_iterations"]],
                  "linear_iterations": [g["linear_iterations"]],
                  "linear_solves": [g["linear_solves"]], "factorizations": [g["factorizations"]],
                  "residual": [g["residuals"][-1] if g["residuals"].size else 0.0],
                  "energy": [g["energy"]]}
        if "kinetic_energy" in g:
            values["kinetic_energy"] = [g["kinetic_energy"]]
        for k, name in enumerate(self.constraints):
            values[f"reaction {name}"] = g["reactions"][k]
        if self.contacts:
            values["contact_area"] = [g["contact_area"]]
        if "penetration" in g and not np.isnan(g["penetration"]):
            values["penetration"] = [g["penetration"]]
        for k, name in enumerate(self.contacts):
            values[f"contact_force {name}"] = g["contact_forces"][k]
            values[f"contact_force_magnitude {name}"] = [g["contact_force_magnitudes"][k]]
            values[f"contact_area {name}"] = [g["contact_areas"][k]]
        return values


def leaves(data):
    """(name or None, data set) of every leaf of a composite data set, in order; names lose the
    "[k]" that the readers append at time step k."""
    out = []
    it = data.NewIterator()
    it.InitTraversal()
    while not it.IsDoneWithTraversal():
        name = None
        if it.HasCurrentMetaData():
            name = it.GetCurrentMetaData().Get(vtkCompositeDataSet.NAME())
        out.append((re.sub(r"\[\d+\]$", "", name) if name else None, it.GetCurrentDataObject()))
        it.GoToNextItem()
    return out


def arrays(attributes):
    """name -> numpy array of every array of a vtkDataSetAttributes or vtkFieldData."""
    return {attributes.GetArrayName(k): vtk_to_numpy(attributes.GetArray(k))
            for k in range(attributes.GetNumberOfArrays())}


def cell_points(grid, corners):
    """#cells x corners point ids of a grid of one cell type."""
    return vtk_to_numpy(grid.GetCells().GetConnectivityArray()).reshape(-1, corners)


def check_state(results, data, state, named):
    """Checks every block of the data set ParaView shows at state `state` against the file."""
    g = results.group(state)
    x = g["x"][()]
    blocks = leaves(data)
    expect(len(blocks) == len(results.blocks) + 1,
           f"{len(blocks)} blocks, expected {len(results.blocks)} and the boundary")
    for (name, grid), (expected, nodes, tets) in zip(blocks, results.blocks):
        where = f"state {state}, block {expected}"
        if named:
            expect(name == expected, f"state {state}: block named {name!r}, expected {expected!r}")
        expect(grid.GetNumberOfPoints() == len(nodes) and grid.GetNumberOfCells() == len(tets),
               f"{where}: {grid.GetNumberOfPoints()} points, {grid.GetNumberOfCells()} cells, "
               f"expected {len(nodes)}, {len(tets)}")
        expect_equal(vtk_to_numpy(grid.GetPoints().GetData()), x[nodes.start:nodes.stop],
                     f"{where}: points")
        expect_equal(cell_points(grid, 4), results.tets[tets.start:tets.stop] - nodes.start,
                     f"{where}: tets")
        point = arrays(grid.GetPointData())
        expected_point = results.node_fields + (["depth"] if results.depth is not None else [])
        expect(sorted(point) == sorted(expected_point),
               f"{where}: point arrays {sorted(point)}, expected {sorted(expected_point)}")
        for field in results.node_fields:
            expect_equal(point[field], results.node_field(g, field)[nodes.start:nodes.stop],
                         f"{where}: {field}")
        if results.depth is not None:
            expect_equal(point["depth"], results.depth[nodes.start:nodes.stop], f"{where}: depth")
        cell = arrays(grid.GetCellData())
        expect(sorted(cell) == sorted(results.tet_fields),
               f"{where}: cell arrays {sorted(cell)}, expected {sorted(results.tet_fields)}")
        for field in results.tet_fields:
            expect_equal(cell[field], g[field][tets.start:tets.stop], f"{where}: {field}")
        expect(grid.GetFieldData().GetNumberOfArrays() == 0, f"{where}: unexpected field data")

    name, boundary = blocks[-1]
    where = f"state {state}, boundary"
    if named:
        expect(name == "boundary", f"state {state}: last block named {name!r}, not 'boundary'")
    expect_equal(vtk_to_numpy(boundary.GetPoints().GetData()), x, f"{where}: points")
    expect_equal(cell_points(boundary, 3), results.tris, f"{where}: triangles")
    point = arrays(boundary.GetPointData())
    expected_point = (["displacement"] if "displacement" in results.node_fields else []) + (
        ["depth"] if results.depth is not None else [])
    expect(sorted(point) == sorted(expected_point),
           f"{where}: point arrays {sorted(point)}, expected {sorted(expected_point)}")
    if "displacement" in point:
        expect_equal(point["displacement"], results.node_field(g, "displacement"),
                     f"{where}: displacement")
    cell = arrays(boundary.GetCellData())
    expect(sorted(cell) == sorted(["body"] + results.triangle_fields),
           f"{where}: cell arrays {sorted(cell)}")
    expect_equal(cell["body"], results.f["mesh/tri_body"][:], f"{where}: body")
    for field in results.triangle_fields:
        expect_equal(cell[field], g[field][()], f"{where}: {field}")
    shown = arrays(boundary.GetFieldData())
    stored = results.field_data(state)
    expect(sorted(shown) == sorted(stored),
           f"{where}: field data {sorted(shown)}, expected {sorted(stored)}")
    for key, values in stored.items():
        expect_equal(np.ravel(shown[key]).astype(float), np.ravel(values).astype(float),
                     f"{where}: field data {key}")


def check_reader(results, reader_name, xmf):
    """Checks one reader on one sidecar; returns '' or what failed."""
    reader = READERS[reader_name](xmf)
    try:
        times = reader.TimestepValues
        times = [times] if isinstance(times, float) else list(times)
        expect(times == results.times,
               f"time steps {times[:3]}...{times[-1:]} ({len(times)}), expected "
               f"{results.times[:3]}...{results.times[-1:]} ({len(results.times)})")
        for state in sorted({0, len(times) // 2, len(times) - 1}):
            reader.UpdatePipeline(times[state])
            check_state(results, servermanager.Fetch(reader), state, NAMED[reader_name])
        for field in ("stress", "strain"):
            if field in results.tet_fields:
                info = reader.CellData[field]
                names = [info.GetComponentName(k) for k in range(info.GetNumberOfComponents())]
                expect(names == TENSOR_COMPONENTS, f"{field} components {names}")
        return ""
    except CheckFailed as failure:
        return str(failure)
    finally:
        Delete(reader)


def summary(results, name):
    """Two lines describing what the sidecar shows."""
    blocks = ", ".join(f"{b} {len(n)}/{len(t)}" for b, n, t in results.blocks)
    fields = results.node_fields + (["depth"] if results.depth is not None else [])
    static = results.results.analysis == "static"
    settled = sum(1 for t in results.times if t > 1) if static else 0
    span = ("load 0 ... 1" + (f", {settled} settling steps" if settled else "") if static
            else f"t = 0 ... {results.times[-1]:g} s")
    return (f"{name}: {len(results.times)} states, {span}; "
            f"blocks (points/cells) {blocks}, boundary {len(results.X)}/{len(results.tris)}\n"
            f"  node: {' '.join(fields) or '-'}; tet: {' '.join(results.tet_fields) or '-'}; "
            f"boundary: body {' '.join(results.triangle_fields)}; "
            f"field data: {len(results.field_data(len(results.times) - 1))} values per step")


def main(paths):
    if not paths:
        print(__doc__.strip().splitlines()[2].strip(), file=sys.stderr)
        return 2
    failed = False
    for path in paths:
        h5_path = os.path.abspath(path)  # the Xdmf3 readers resolve the HDF5 file against its folder
        base = os.path.splitext(h5_path)[0]
        sidecars = {reader: base + SIDECAR[reader] for reader in READERS}
        missing = [p for p in [h5_path, *sidecars.values()] if not os.path.isfile(p)]
        if missing:
            print(f"{path}: no {', '.join(missing)}", file=sys.stderr)
            failed = True
            continue
        with ResultsReader(h5_path) as h5:
            results = Results(h5)
            print(summary(results, os.path.basename(path)))
            verdicts = []
            for reader_name in READERS:
                problem = check_reader(results, reader_name, sidecars[reader_name])
                failed |= bool(problem)
                verdicts.append(f"{reader_name}: {'FAILED: ' + problem if problem else 'ok'}")
            print("  " + "; ".join(verdicts))
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
