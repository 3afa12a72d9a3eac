#!/usr/bin/python3
"""Plot per-step convergence and energy of a depthfem results file to a PNG.

    plot_series.py RESULT.h5 OUT.png

Three stacked panels against the load factor (static) or time (dynamic): Newton iterations,
the final Newton residual norm (log scale) and the energy [J]. Errors print one line to stderr
and exit with status 1.
"""

import argparse
import sys

import matplotlib

matplotlib.use("Agg")  # no display needed
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from render import open_results, run_main, save_figure, scene_name  # noqa: E402


def read_series(path):
    """Per-step arrays: load, Newton iterations, final residual (nan if none), energy; and the
    scene name and whether the run is dynamic."""
    with open_results(path) as r:
        return (r.series("load"), r.series("newton_iterations"), r.last_residuals(),
                r.series("energy"), scene_name(r), r.analysis in ("dynamic", "quasistatic"))


def plot_series(path, out):
    """Draws the three panels for results file `path` and writes the PNG `out`."""
    load, newton, residual, energy, name, dynamic = read_series(path)
    fig, (ax_newton, ax_residual, ax_energy) = plt.subplots(3, 1, sharex=True, figsize=(7, 8))
    ax_newton.plot(load, newton, "o-")
    ax_newton.set_ylabel("Newton iterations")
    ax_newton.yaxis.get_major_locator().set_params(integer=True)
    ax_residual.semilogy(load, residual, "o-", color="tab:red")
    ax_residual.set_ylabel("final residual norm")
    ax_energy.plot(load, energy, "o-", color="tab:green")
    ax_energy.set_ylabel("energy [J]")
    ax_energy.set_xlabel("time [s]" if dynamic else "load factor")
    for ax in (ax_newton, ax_residual, ax_energy):
        ax.grid(True, alpha=0.3)
    fig.suptitle(f"{name}: {len(load)} steps" if name else f"{len(load)} steps")
    fig.tight_layout()
    save_figure(fig, out)


def main(argv):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("result", help="results file (.h5)")
    parser.add_argument("out", help="image to write (.png)")
    args = parser.parse_args(argv)
    plot_series(args.result, args.out)


if __name__ == "__main__":
    run_main(main, sys.argv[1:])
