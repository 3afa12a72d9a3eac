#!/usr/bin/python3
"""Render the deformed boundary of one step of a depthfem results file to a PNG.

    render.py RESULT.h5 OUT.png [--step N] [--view ELEV AZIM]
              [--color displacement|depth|body] [--reference]

Faces are coloured by the mean over their nodes of |x - X| [m] or the material depth [m], or by
the body they belong to. Errors print one line to stderr and exit with status 1.
"""

import argparse
import json
import os
import sys

import h5py
import matplotlib

matplotlib.use("Agg")  # no display needed
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from mpl_toolkits.mplot3d.art3d import Poly3DCollection  # noqa: E402


class ToolError(Exception):
    """A problem with the input, reported as one line."""


def open_results(path):
    """Opens a depthfem results file read-only; ToolError if missing, not HDF5 or foreign."""
    if not os.path.isfile(path):
        raise ToolError(f"{path}: no such results file")
    try:
        f = h5py.File(path, "r")
    except OSError:
        raise ToolError(f"{path}: not an HDF5 file") from None
    if not all(group in f for group in ("mesh", "run", "steps")):
        raise ToolError(f"{path}: not a depthfem results file (no /mesh, /run or /steps)")
    return f


def step_names(f, path):
    """Names of the step groups in step order ("000001", ...); ToolError if there are none."""
    names = sorted(f["steps"])
    if not names:
        raise ToolError(f"{path}: has no steps")
    return names


def scene_name(f):
    """The "name" of the scene JSON stored in /run, or None."""
    try:
        return json.loads(f["run"].attrs["scene"]).get("name")
    except (KeyError, ValueError, AttributeError):
        return None


def is_dynamic(f):
    """Whether the run is dynamic, so that a step's "load" is its time [s]."""
    return f["run"].attrs.get("analysis") == "dynamic"


def load_label(f, load):
    """'t = 0.5 s' for a dynamic run, 'load 0.5' otherwise."""
    return f"t = {load:g} s" if is_dynamic(f) else f"load {load:g}"


def run_main(main, argv):
    """Runs main(argv), turning a ToolError into one line on stderr and exit status 1."""
    try:
        main(argv)
    except ToolError as error:
        print(f"{os.path.basename(sys.argv[0])}: {error}", file=sys.stderr)
        sys.exit(1)


def face_values(f, color, X, x, tris):
    """Per-face values (#tris) of the field `color` and its colorbar label."""
    if color == "displacement":
        return np.linalg.norm(x - X, axis=1)[tris].mean(axis=1), "|x - X| [m]"
    if color == "depth":
        return f["mesh/depth"][:][tris].mean(axis=1), "depth [m]"
    return f["mesh/tri_body"][:].astype(float), "body"


def set_equal_axes(ax, points):
    """Axis limits around `points` (#points x 3) with the same scale on all three axes."""
    lo, hi = points.min(axis=0), points.max(axis=0)
    extent = np.maximum(hi - lo, 1e-3 * max((hi - lo).max(), 1e-12))
    center = (lo + hi) / 2
    ax.set_xlim(center[0] - extent[0] / 2, center[0] + extent[0] / 2)
    ax.set_ylim(center[1] - extent[1] / 2, center[1] + extent[1] / 2)
    ax.set_zlim(center[2] - extent[2] / 2, center[2] + extent[2] / 2)
    ax.set_box_aspect(extent)
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_zlabel("z [m]", labelpad=10)


def render(path, out, step=None, view=(25.0, -60.0), color="displacement", reference=False):
    """Draws step `step` (default: the last) of results file `path` and writes the PNG `out`."""
    with open_results(path) as f:
        names = step_names(f, path)
        name = names[-1] if step is None else f"{step:06d}"
        if name not in names:
            raise ToolError(f"{path}: no step {step} (steps {int(names[0])} to {int(names[-1])})")
        tris = f["mesh/tris"][:]
        X = f["mesh/X"][:]
        x = f[f"steps/{name}/x"][:]
        values, label = face_values(f, color, X, x, tris)
        body_names = list(f["mesh/body_names"].asstr()[:])
        where = f"step {int(name)}, {load_label(f, f['steps'][name].attrs['load'])}"
        title = f"{scene_name(f)}: {where}" if scene_name(f) else where

    fig = plt.figure(figsize=(8, 7))
    ax = fig.add_subplot(projection="3d")
    if reference:
        ax.add_collection3d(
            Poly3DCollection(X[tris], facecolor="lightgrey", edgecolor="none", alpha=0.15)
        )
    if color == "body":
        cmap = plt.get_cmap("tab10", max(len(body_names), 1))
        norm = matplotlib.colors.Normalize(-0.5, max(len(body_names), 1) - 0.5)
    else:
        cmap = plt.get_cmap("viridis")
        lo, hi = values.min(), values.max()
        norm = matplotlib.colors.Normalize(lo, hi if hi > lo else lo + 1)  # a constant field too
    ax.add_collection3d(
        Poly3DCollection(x[tris], facecolors=cmap(norm(values)), edgecolor=(0, 0, 0, 0.15),
                         linewidth=0.3)
    )
    set_equal_axes(ax, np.vstack([x, X]) if reference else x)
    ax.view_init(elev=view[0], azim=view[1])
    bar = fig.colorbar(plt.cm.ScalarMappable(norm=norm, cmap=cmap), ax=ax, shrink=0.6, pad=0.12, label=label)
    if color == "body":
        bar.set_ticks(range(len(body_names)), labels=body_names)
    ax.set_title(title)
    save_figure(fig, out)


def save_figure(fig, out):
    """Writes the figure as a 150 dpi PNG and closes it; ToolError if it cannot be written."""
    try:
        fig.savefig(out, dpi=150)
    except OSError as error:
        raise ToolError(f"{out}: cannot write ({error.strerror})") from None
    plt.close(fig)


def main(argv):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("result", help="results file (.h5)")
    parser.add_argument("out", help="image to write (.png)")
    parser.add_argument("--step", type=int, help="step index (default: the last step)")
    parser.add_argument("--view", type=float, nargs=2, default=(25.0, -60.0),
                        metavar=("ELEV", "AZIM"), help="camera elevation and azimuth [deg]")
    parser.add_argument("--color", choices=("displacement", "depth", "body"),
                        default="displacement", help="field that colours the faces")
    parser.add_argument("--reference", action="store_true",
                        help="also draw the reference configuration, light and transparent")
    args = parser.parse_args(argv)
    render(args.result, args.out, args.step, args.view, args.color, args.reference)


if __name__ == "__main__":
    run_main(main, sys.argv[1:])
