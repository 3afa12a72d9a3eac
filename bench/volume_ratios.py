#!/usr/bin/env python3
"""Smallest volume ratios of a run, step by step: of single tets (current over rest volume) and of
nodes (the volume of the tets around a node, current over rest, as the nodal-pressure
formulation measures it), over the tets of the element regions named (all regions of deformable
bodies by default). One CSV row per step.

    /usr/bin/python3 bench/volume_ratios.py RESULT.h5 [OUT.csv] [--regions soft_tissue ...]
"""
import argparse
import sys

import numpy as np

sys.path.insert(0, "apps/tools")
from results import Results  # noqa: E402


def tet_volumes(x, tets):
    """Signed volumes of the tets (#tets x 4 node indices) at positions x (#nodes x 3)."""
    a, b, c, d = (x[tets[:, k]] for k in range(4))
    return np.einsum("ij,ij->i", b - a, np.cross(c - a, d - a)) / 6.0


def nodal_volumes(volumes, tets, num_nodes):
    """A quarter of each tet's volume summed at its four nodes."""
    out = np.zeros(num_nodes)
    for k in range(4):
        np.add.at(out, tets[:, k], 0.25 * volumes)
    return out


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("results")
    parser.add_argument("out", nargs="?", default="-")
    parser.add_argument("--regions", nargs="*", help="element regions (default: deformable ones)")
    args = parser.parse_args()
    with Results(args.results) as r:
        mesh = r.f["mesh"]
        X, tets = mesh["X"][:], mesh["tets"][:]
        names = [n.decode() for n in mesh["region_names"][:]]
        materials = [m.decode() for m in mesh["region_materials"][:]]
        wanted = args.regions or [n for n, m in zip(names, materials) if m != "rigid"]
        unknown = sorted(set(wanted) - set(names))
        if unknown:
            sys.exit(f"volume_ratios.py: no region {', '.join(unknown)} (regions: {', '.join(names)})")
        keep = np.isin(mesh["tet_region"][:], [names.index(n) for n in wanted])
        tets = tets[keep]
        rest = tet_volumes(X, tets)
        used = np.unique(tets)
        rest_nodal = nodal_volumes(rest, tets, len(X))[used]
        loads = r.series("load")
        rows = ["step,load,smallest_tet_ratio,tets_below_half,smallest_nodal_ratio,nodes_below_half"]
        for k in range(r.num_steps):
            now = tet_volumes(r.step(k)["x"], tets)
            tet_ratio = now / rest
            nodal_ratio = nodal_volumes(now, tets, len(X))[used] / rest_nodal
            rows.append(f"{r.index[k]},{loads[k]:.4f},{tet_ratio.min():.5f},"
                        f"{int((tet_ratio < 0.5).sum())},{nodal_ratio.min():.5f},"
                        f"{int((nodal_ratio < 0.5).sum())}")
    text = "\n".join(rows) + "\n"
    if args.out == "-":
        sys.stdout.write(text)
    else:
        with open(args.out, "w") as f:
            f.write(text)


if __name__ == "__main__":
    main()
