#!/usr/bin/python3
"""Compares the positions of two results files of one scene, step by step (a distributed run
against the serial one, say): both must hold the same load factors or times.

    compare_runs.py A.h5 B.h5 [--tolerance T]

Prints, per step, the largest difference of a node's position over the largest displacement of
any node from its reference position in A, and the worst of them; with --tolerance, exits with 1
when the worst is above T (or the steps differ).
"""

import argparse
import sys

import numpy as np

from results import Results, ResultsError


def compare(path_a, path_b):
    """Per step (load, largest |x_a - x_b| / largest |x_a - X|)."""
    rows = []
    with Results(path_a) as a, Results(path_b) as b:
        if a.num_steps != b.num_steps:
            raise ResultsError(f"{path_a} has {a.num_steps} steps, {path_b} {b.num_steps}")
        X = a.f["mesh/X"][:]
        loads_a, loads_b = a.series("load"), b.series("load")
        for k in range(a.num_steps):
            if loads_a[k] != loads_b[k]:
                raise ResultsError(f"step {k}: load {loads_a[k]} in {path_a}, {loads_b[k]} in {path_b}")
            xa, xb = a.step(k)["x"], b.step(k)["x"]
            scale = np.linalg.norm(xa - X, axis=1).max()
            rows.append((loads_a[k], np.linalg.norm(xa - xb, axis=1).max() / scale))
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
    for k, (load, d) in enumerate(rows):
        print(f"step {k:4d}  load {load:.6g}  max |dx| / max |u| {d:.3e}")
    worst = max(d for _, d in rows)
    print(f"worst {worst:.3e}")
    if args.tolerance is not None and not worst <= args.tolerance:
        print(f"compare_runs: error: {worst:.3e} above the tolerance {args.tolerance:g}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
