#!/usr/bin/python3
"""Compares the positions of two results files of one scene at the load factors or times both
completed (a distributed run against the serial one, say); both must end at the same one. Steps
at the same load (the settle steps after the full load) are paired in order.

    compare_runs.py A.h5 B.h5 [--tolerance T]

Prints, per common step, the largest difference of a node's position over the largest displacement of
any node from its reference position in A, and the worst of them; with --tolerance, exits with 1
when the worst is above T (or the steps differ).
"""

import argparse
import sys

import numpy as np

from results import Results, ResultsError


def compare(path_a, path_b):
    """Per load factor or time both runs completed (the last one must be one):
    (load, largest |x_a - x_b| / largest |x_a - X|)."""
    rows = []
    with Results(path_a) as a, Results(path_b) as b:
        X = a.f["mesh/X"][:]
        loads_a, loads_b = list(a.series("load")), list(b.series("load"))
        if not loads_a or not loads_b or loads_a[-1] != loads_b[-1]:
            raise ResultsError(f"the runs end at different loads ({path_a}: {loads_a[-1:]}, "
                               f"{path_b}: {loads_b[-1:]})")
        # The n-th step at a load in A against the n-th at that load in B: a static scene's
        # settle steps all hold the full load.
        steps_b = {}
        for k, load in enumerate(loads_b):
            steps_b.setdefault(load, []).append(k)
        seen = {}
        for k, load in enumerate(loads_a):
            n = seen[load] = seen.get(load, -1) + 1
            if n >= len(steps_b.get(load, [])):
                continue
            xa, xb = a.step(k)["x"], b.step(steps_b[load][n])["x"]
            scale = np.linalg.norm(xa - X, axis=1).max()
            rows.append((load, np.linalg.norm(xa - xb, axis=1).max() / scale))
    return rows


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("a")
    parser.add_argument("b")
    parser.add_argument("--tolerance", type=float)
    args = parser.parse_args()
    try:
        rows = compare(args.a, args.b)
    except (ResultsError, KeyError) as e:
        print(f"compare_runs: error: {e}", file=sys.stderr)
        return 1
    for load, d in rows:
        print(f"load {load:.6g}  max |dx| / max |u| {d:.3e}")
    worst = max(d for _, d in rows)
    print(f"worst {worst:.3e}")
    if args.tolerance is not None and not worst <= args.tolerance:
        print(f"compare_runs: error: {worst:.3e} above the tolerance {args.tolerance:g}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
