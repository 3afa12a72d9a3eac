#!/usr/bin/env python3
"""Compares two knee runs (results files of a knee-flexion scene) step by step: what a change to
the solver must keep. Prints, per run, the steps, Newton iterations, the deepest penetration of
any step and the smallest tet volume ratio of any step, and between the runs the largest
difference of the patella's path (centroid relative to the femur, at the angles both reached),
the relative difference of the energy at the last step and the largest node distance between
the last states.

Usage: knee_compare.py BEFORE.h5 AFTER.h5"""
import sys

import numpy as np

from knee_figures import Run, patella_path
from render import ToolError, open_results, run_main


def volume_ratios(X, x, tets):
    def volumes(p):
        a, b, c, d = (p[tets[:, k]] for k in range(4))
        return np.einsum("ij,ij->i", np.cross(b - a, c - a), d - a)
    return volumes(x) / volumes(X)


def summary(path):
    run = Run(path)
    with open_results(path) as r:
        iterations = r.series("newton_iterations")
        penetration = r.series("penetration")
        energy = r.series("energy")
    leg = run.tet_body == run.bodies.index("leg")
    smallest = min(volume_ratios(run.X, x, run.tets[leg]).min() for x in run.x)
    return run, iterations, penetration, energy, smallest


def main(argv):
    if len(argv) != 2:
        raise ToolError("usage: knee_compare.py BEFORE.h5 AFTER.h5")
    runs = [summary(p) for p in argv]
    for path, (run, iterations, penetration, energy, smallest) in zip(argv, runs):
        print(f"{path}: {len(run.x)} steps to {run.angles()[-1]:.1f} deg, "
              f"{int(iterations.sum())} Newton iterations, deepest penetration "
              f"{1e3 * penetration.max():.3f} mm, smallest volume ratio {smallest:.4f}")
    (a, *_), (b, *_) = runs
    pa, pb = patella_path(a), patella_path(b)
    common = np.intersect1d(np.round(pa[:, 0], 6), np.round(pb[:, 0], 6))
    ra = pa[np.isin(np.round(pa[:, 0], 6), common)]
    rb = pb[np.isin(np.round(pb[:, 0], 6), common)]
    path_difference = np.hypot(ra[:, 1] - rb[:, 1], ra[:, 2] - rb[:, 2]).max()
    ea, eb = runs[0][3][-1], runs[1][3][-1]
    distance = np.linalg.norm(a.x[-1] - b.x[-1], axis=1)
    print(f"patella path: largest difference {path_difference:.3f} mm over {len(common)} angles")
    print(f"energy at the last step: {ea:.6e} and {eb:.6e} J, relative difference "
          f"{abs(eb - ea) / abs(ea):.2e}")
    print(f"last states: largest node distance {1e3 * distance.max():.3f} mm "
          f"(node {int(distance.argmax())})")


if __name__ == "__main__":
    run_main(main, sys.argv[1:])
