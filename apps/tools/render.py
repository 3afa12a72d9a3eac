#!/usr/bin/python3
"""Render the deformed boundary of one step of a depthfem results file to a PNG.

    render.py RESULT.h5 OUT.png [--step N] [--view ELEV AZIM] [--color FIELD[:COMPONENT]]
              [--reference] [--list]

Faces are coloured by any field the file holds (--list prints them): node fields (displacement,
velocity, depth) by the mean over the face's nodes, tet fields (stress, von_mises, strain,
volume_ratio) by the tet the face belongs to, triangle fields (contact_pressure, contact_traction,
contact_gap, contact_fraction) directly, and body by the body's name. Vectors are shown by their
magnitude or a component (x, y, z); symmetric tensors by a component (xx, yy, zz, xy, yz, xz).
The three axes share one scale. Errors print one line to stderr and exit with status 1.
"""

import argparse
import os
import sys

import matplotlib

matplotlib.use("Agg")  # no display needed
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.ticker import FormatStrFormatter, MaxNLocator  # noqa: E402
from mpl_toolkits.mplot3d.art3d import Poly3DCollection  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from results import Results, ResultsError  # noqa: E402


class ToolError(Exception):
    """A problem with the input, reported as one line."""


def open_results(path):
    """Opens a depthfem results file (results.Results) that has at least one completed step;
    ToolError if it is missing, not HDF5, foreign or without steps."""
    if not os.path.isfile(path):
        raise ToolError(f"{path}: no such results file")
    try:
        results = Results(path)
    except ResultsError as error:
        raise ToolError(str(error)) from None
    if not results.num_steps:
        results.close()
        raise ToolError(f"{path}: has no steps")
    return results


def scene_name(results):
    """The "name" of the scene JSON stored in /run, or None."""
    try:
        return results.scene().get("name")
    except (KeyError, ValueError, AttributeError):
        return None


def load_label(results, load):
    """'t = 0.5 s' for a time-dependent run, 'load 0.5' otherwise."""
    dynamic = results.analysis in ("dynamic", "quasistatic")
    return f"t = {load:g} s" if dynamic else f"load {load:g}"


def run_main(main, argv):
    """Runs main(argv), turning a ToolError into one line on stderr and exit status 1."""
    try:
        main(argv)
    except ToolError as error:
        print(f"{os.path.basename(sys.argv[0])}: {error}", file=sys.stderr)
        sys.exit(1)


# Units of the fields a results file can hold (apps/README.md), by the name --color takes.
UNITS = {
    "displacement": "m", "velocity": "m/s", "depth": "m", "stress": "Pa", "von_mises": "Pa",
    "strain": "-", "volume_ratio": "-", "contact_pressure": "Pa", "contact_traction": "Pa",
    "contact_gap": "m", "contact_fraction": "-", "body": None,
}
# Datasets of a step group under another name than --color's.
DATASET = {"velocity": "v"}
VECTOR_COMPONENTS = ("x", "y", "z")
TENSOR_COMPONENTS = ("xx", "yy", "zz", "xy", "yz", "xz")


def available_fields(f, step):
    """The fields --color can show at step `step` (results.Step), in UNITS order."""
    def present(name):
        if name in ("body", "displacement"):  # displacement: x - X where not written
            return True
        if name == "depth":
            return "depth" in f["mesh"]
        return DATASET.get(name, name) in step
    return [name for name in UNITS if present(name)]


def field_data(f, name, step):
    """The array of field `name` at step `step` (results.Step)."""
    if name == "depth":
        return f["mesh/depth"][:]
    if name == "displacement" and "displacement" not in step:
        return step["x"] - f["mesh/X"][:]
    return step[DATASET.get(name, name)]


def field_values(f, name, component, step, x, tris):
    """Per-face values (#tris) of field `name` (component or None) at a step, and a label."""
    fields = available_fields(f, step)
    if name not in fields:
        raise ToolError(f"no field '{name}' in this step (fields: {', '.join(fields)})")
    if name == "body":
        if component:
            raise ToolError("body has no components")
        return f["mesh/tri_body"][:].astype(float), "body"
    data = field_data(f, name, step)
    if data.ndim == 2 and data.shape[1] == 3:
        choices = VECTOR_COMPONENTS
    elif data.ndim == 2 and data.shape[1] == 6:
        choices = TENSOR_COMPONENTS
        if component is None:
            raise ToolError(f"{name} is a symmetric tensor: choose a component "
                            f"({name}:{'|'.join(choices)})")
    else:
        choices = ()
    if component is not None and component not in choices:
        raise ToolError(f"{name} has no component '{component}'"
                        + (f" (components: {', '.join(choices)})" if choices else ""))
    if data.ndim == 2:
        data = (np.linalg.norm(data, axis=1) if component is None
                else data[:, choices.index(component)])
    shown = f"|{name}|" if choices and component is None else (
        f"{name} {component}" if component else name)
    label = f"{shown} [{UNITS[name]}]"
    rows = data.shape[0]
    if rows == x.shape[0]:
        return data[tris].mean(axis=1), label
    if rows == tris.shape[0]:
        return data, label
    if "tri_tet" not in f["mesh"]:
        raise ToolError(f"{name} is per tet, and the file has no /mesh/tri_tet to find the faces' tets")
    return data[f["mesh/tri_tet"][:]], label


def set_equal_axes(ax, points, ticks=6):
    """Axis limits around `points` (#points x 3) with one scale on all three axes. The longest
    axis gets at most `ticks` ticks, a shorter one proportionally fewer, labelled without
    round-off; an axis under a quarter of the longest is too short on screen for tick labels,
    and a note in the corner gives its range instead."""
    lo, hi = points.min(axis=0), points.max(axis=0)
    longest = max((hi - lo).max(), 1e-12)
    extent = np.maximum(hi - lo, 0.05 * longest)  # a flat body keeps a visible thickness
    center = (lo + hi) / 2
    ranges = []
    for k, (axis, name) in enumerate(zip((ax.xaxis, ax.yaxis, ax.zaxis), "xyz")):
        getattr(ax, f"set_{name}lim")(center[k] - extent[k] / 2, center[k] + extent[k] / 2)
        if extent[k] < 0.25 * longest:
            axis.set_major_locator(MaxNLocator(1))
            axis.set_ticklabels([])
            axis.set_label_text(name)
            ranges.append(f"{name} from {lo[k]:.3g} to {hi[k]:.3g} m")
        else:
            axis.set_major_locator(MaxNLocator(max(2, round(ticks * extent[k] / longest))))
            axis.set_major_formatter(FormatStrFormatter("%g"))
            axis.set_label_text(f"{name} [m]")
        axis.labelpad = 8
    if ranges:
        ax.text2D(0.0, 0.0, ", ".join(ranges), transform=ax.transAxes, fontsize=8)
    ax.set_box_aspect(extent, zoom=0.85)  # room for the z label
    ax.tick_params(labelsize=8)


def parse_color(text):
    """'FIELD' or 'FIELD:COMPONENT' as (field, component or None)."""
    name, _, component = text.partition(":")
    return name, component or None


def render(path, out, step=None, view=(25.0, -60.0), color="displacement", reference=False):
    """Draws step `step` (default: the last) of results file `path` and writes the PNG `out`."""
    name_of_field, component = parse_color(color)
    with open_results(path) as results:
        group = chosen_step(results, path, step)
        f = results.f
        index = group["index"]
        tris = f["mesh/tris"][:]
        X = f["mesh/X"][:]
        x = group["x"]
        try:
            values, label = field_values(f, name_of_field, component, group, x, tris)
        except ToolError as error:
            raise ToolError(f"{path}: step {index}: {error}") from None
        body_names = list(f["mesh/body_names"].asstr()[:])
        where = f"step {index}, {load_label(results, group['load'])}"
        title = f"{scene_name(results)}: {where}" if scene_name(results) else where

    fig = plt.figure(figsize=(8, 7))
    ax = fig.add_subplot(projection="3d")
    if reference:
        ax.add_collection3d(
            Poly3DCollection(X[tris], facecolor="lightgrey", edgecolor="none", alpha=0.15)
        )
    if name_of_field == "body":
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
    bar = fig.colorbar(plt.cm.ScalarMappable(norm=norm, cmap=cmap), ax=ax, shrink=0.6,
                       pad=0.02, location="bottom", label=label)
    if name_of_field == "body":
        bar.set_ticks(range(len(body_names)), labels=body_names)
    else:
        bar.ax.xaxis.set_major_locator(MaxNLocator(6))
    ax.set_title(title)
    save_figure(fig, out, [axis.label for axis in (ax.xaxis, ax.yaxis, ax.zaxis)])


def save_figure(fig, out, extra_artists=(), dpi=150):
    """Writes the figure as a PNG (150 dpi unless told), trimmed to its content and `extra_artists` (which the
    trimming would miss, such as the axis labels of a 3D plot), and closes it; ToolError if it
    cannot be written."""
    try:
        fig.savefig(out, dpi=dpi, bbox_inches="tight", bbox_extra_artists=list(extra_artists))
    except OSError as error:
        raise ToolError(f"{out}: cannot write ({error.strerror})") from None
    plt.close(fig)


def chosen_step(results, path, step):
    """The datasets of step `step` (its index; default: the last); ToolError if there is none."""
    try:
        return results.step(-1 if step is None else results.row_of(step))
    except ResultsError as error:
        raise ToolError(str(error)) from None


def list_fields(path, step=None):
    """Prints the fields --color can show at a step (default: the last), with their shapes."""
    with open_results(path) as results:
        f = results.f
        group = chosen_step(results, path, step)
        for name in available_fields(f, group):
            if name == "body":
                print("body (names)")
                continue
            data = field_data(f, name, group)
            parts = ({3: VECTOR_COMPONENTS, 6: TENSOR_COMPONENTS}.get(data.shape[1], ())
                     if data.ndim == 2 else ())
            print(f"{name} [{UNITS[name]}]" + (f" components {', '.join(parts)}" if parts else ""))


def main(argv):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("result", help="results file (.h5)")
    parser.add_argument("out", nargs="?", help="image to write (.png)")
    parser.add_argument("--step", type=int, help="step index (default: the last step)")
    parser.add_argument("--view", type=float, nargs=2, default=(25.0, -60.0),
                        metavar=("ELEV", "AZIM"), help="camera elevation and azimuth [deg]")
    parser.add_argument("--color", default="displacement", metavar="FIELD[:COMPONENT]",
                        help="field that colours the faces (default: |displacement|)")
    parser.add_argument("--reference", action="store_true",
                        help="also draw the reference configuration, light and transparent")
    parser.add_argument("--list", action="store_true", help="print the fields and exit")
    args = parser.parse_args(argv)
    if args.list:
        list_fields(args.result, args.step)
        return
    if args.out is None:
        parser.error("the image to write (OUT.png) is missing")
    render(args.result, args.out, args.step, args.view, args.color, args.reference)


if __name__ == "__main__":
    run_main(main, sys.argv[1:])
