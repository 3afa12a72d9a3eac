#!/usr/bin/python3
"""Figures of a knee-flexion run (apps/scenes/knee_flexion*.json), like the paper's figures 10-12.

    knee_figures.py RESULT.h5 OUT_DIR [--gif] [--step N]

Writes into OUT_DIR:
  knee_side.png     the leg straight (reference) and bent (step N, default the last), lateral view
  knee_cutaway.png  the bent knee cut by the sagittal plane through the flexion axis centre,
                    soft tissue and patella coloured by material depth, bones grey
  knee_fold.png     close-up of the skin at the back of the bent knee
  knee_patella.png  the patella's path relative to the femur against the flexion angle
  knee_patella.csv  the same numbers: angle [deg], patella centroid relative to the axis centre
                    (anterior, superior) [mm], distance travelled [mm]
  knee_flexion.gif  (with --gif) every step, lateral view

The flexion angle of a step is its load factor times the angle of the scene's first "rotated"
condition; the body names femur, tibia and leg and the node sets skin, thigh_cut, shin_cut and
patella are those of apps/scenes/knee/knee.msh. Surfaces are drawn by an orthographic painter's
algorithm (triangles sorted far to near, Lambert shading). Errors print one line and exit 1.
"""

import argparse
import csv
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from render import ToolError, open_results, run_main, save_figure  # noqa: E402

import matplotlib  # noqa: E402

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.animation import PillowWriter  # noqa: E402
from matplotlib.collections import PolyCollection  # noqa: E402

SKIN = (0.93, 0.76, 0.66)
# The meshes' thousands of shaded triangles make large PNGs: 100 dpi keeps each under 300 KB.
# The animation (53 frames of the skin) at 40 dpi stays under 300 KB too.
FIGURE_DPI = 100
GIF_DPI = 40
BONE = (0.85, 0.85, 0.80)


class Run:
    """What the figures need from a results file."""

    def __init__(self, path):
        with open_results(path) as results:
            f = results.f
            self.X = f["mesh/X"][:]
            self.tets = f["mesh/tets"][:]
            self.tris = f["mesh/tris"][:]
            self.tet_body = f["mesh/tet_body"][:]
            self.tri_body = f["mesh/tri_body"][:]
            self.depth = f["mesh/depth"][:]
            self.bodies = list(f["mesh/body_names"].asstr()[:])
            if "node_sets" not in f["mesh"]:
                raise ToolError(f"{path}: has no node sets (not a knee run)")
            self.sets = {k: f["mesh/node_sets"][k][:] for k in f["mesh/node_sets"]}
            self.loads = results.series("load")
            self.x = list(results.series("x"))
            scene = results.scene()
        for body in ("femur", "tibia", "leg"):
            if body not in self.bodies:
                raise ToolError(f"{path}: no body '{body}' (bodies: {', '.join(self.bodies)})")
        for name in ("skin", "patella"):
            if name not in self.sets:
                raise ToolError(f"{path}: no node set '{name}'")
        rotated = [b for b in scene.get("boundary", []) if b.get("type") == "rotated"]
        if not rotated:
            raise ToolError(f"{path}: the scene has no rotated boundary condition")
        self.total_angle = float(rotated[0]["angle_deg"])
        self.center = np.array(rotated[0]["center"], float)
        self.axis = np.array(rotated[0]["axis"], float) / np.linalg.norm(rotated[0]["axis"])

    def angles(self):
        return self.total_angle * self.loads

    def body_tris(self, body):
        return self.tris[self.tri_body == self.bodies.index(body)]

    def skin_tris(self):
        """Triangles of the leg whose nodes all lie on the skin or a cut section."""
        on = np.zeros(len(self.X), bool)
        for name in ("skin", "thigh_cut", "shin_cut"):
            if name in self.sets:
                on[self.sets[name]] = True
        t = self.body_tris("leg")
        return t[on[t].all(axis=1)]


def camera(azimuth, elevation):
    """Rows: screen right, screen up, viewing direction (into the picture), for a camera turned
    `azimuth` degrees about z from looking along +x (a lateral view of a right leg, anterior to
    the right) and raised by `elevation` degrees."""
    a, e = np.radians(azimuth), np.radians(elevation)
    forward = np.array([np.cos(a) * np.cos(e), np.sin(a) * np.cos(e), -np.sin(e)])
    right = np.cross(forward, [0.0, 0.0, 1.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    return np.array([right, up, forward])


def draw_surface(ax, x, tris, R, color, keep=None):
    """Shaded triangles (#tris x 3 node indices at positions x) seen through camera R, far first;
    `keep` optionally selects triangles by a boolean mask of their centroids."""
    p = x @ R.T  # screen right, up, depth
    corners = p[tris]
    normals = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    facing = normals[:, 2] < 0  # outward normal towards the camera
    mask = facing if keep is None else facing & keep
    corners, normals = corners[mask], normals[mask]
    order = np.argsort(-corners[:, :, 2].mean(axis=1))
    corners, normals = corners[order], normals[order]
    lit = np.abs(normals[:, 2]) / np.maximum(np.linalg.norm(normals, axis=1), 1e-300)
    shade = (0.35 + 0.65 * lit)[:, None] * np.array(color)[None, :]
    ax.add_collection(PolyCollection(corners[:, :, :2], facecolors=np.clip(shade, 0, 1),
                                     edgecolors="none"))
    return p[np.unique(tris[mask])][:, :2] if mask.any() else np.zeros((0, 2))


def frame_axes(ax, points, margin=0.01):
    lo, hi = points.min(axis=0) - margin, points.max(axis=0) + margin
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_aspect("equal")
    ax.set_axis_off()


def side_view(run, ax, x, title):
    R = camera(0, 10)
    pts = draw_surface(ax, x, run.skin_tris(), R, SKIN)
    frame_axes(ax, pts)
    ax.set_title(title)


def figure_side(run, step, out):
    fig, axes = plt.subplots(1, 2, figsize=(10, 6))
    side_view(run, axes[0], run.X, "straight (reference)")
    side_view(run, axes[1], run.x[step], f"bent {run.angles()[step]:.0f} deg (step {step})")
    fig.suptitle("knee flexion: skin, lateral view")
    fig.tight_layout()
    save_figure(fig, os.path.join(out, "knee_side.png"), dpi=FIGURE_DPI)


def section(x, tets, values, plane_x):
    """Polygons where the plane x = plane_x cuts the tets (as (y, z)) and the mean of `values`
    (per node) over each polygon's vertices."""
    polys, vals = [], []
    P = x[tets]
    side = P[:, :, 0] - plane_x
    cut = (side.min(axis=1) < 0) & (side.max(axis=1) > 0)
    for t in np.nonzero(cut)[0]:
        pts, v = [], []
        for a in range(4):
            for b in range(a + 1, 4):
                da, db = side[t, a], side[t, b]
                if da * db < 0:
                    s = da / (da - db)
                    pts.append(P[t, a] + s * (P[t, b] - P[t, a]))
                    v.append(values[tets[t, a]] + s * (values[tets[t, b]] - values[tets[t, a]]))
        pts = np.array(pts)[:, 1:]
        c = pts.mean(axis=0)
        order = np.argsort(np.arctan2(pts[:, 1] - c[1], pts[:, 0] - c[0]))
        polys.append(pts[order])
        vals.append(np.mean(v))
    return polys, np.array(vals)


def figure_cutaway(run, step, out):
    x = run.x[step]
    plane = run.center[0]
    fig, ax = plt.subplots(figsize=(7, 8))
    # Seen from the lateral side (-x): the screen shows -y to the right, z up.
    to_screen = np.array([[-1.0, 0.0], [0.0, 1.0]])
    leg = run.tet_body == run.bodies.index("leg")
    polys, vals = section(x, run.tets[leg], run.depth, plane)
    norm = matplotlib.colors.Normalize(0, vals.max() * 1e3 if len(vals) else 1)
    ax.add_collection(PolyCollection([p @ to_screen.T for p in polys],
                                     facecolors=plt.get_cmap("viridis")(norm(vals * 1e3)),
                                     edgecolors=(0, 0, 0, 0.25), linewidths=0.2))
    everything = [p @ to_screen.T for p in polys]
    for bone in ("femur", "tibia"):
        b = run.tet_body == run.bodies.index(bone)
        bp, _ = section(x, run.tets[b], run.depth, plane)
        ax.add_collection(PolyCollection([p @ to_screen.T for p in bp], facecolors=BONE,
                                         edgecolors=(0, 0, 0, 0.15), linewidths=0.2))
        everything += [p @ to_screen.T for p in bp]
    frame_axes(ax, np.vstack(everything), 0.005)
    fig.colorbar(plt.cm.ScalarMappable(norm=norm, cmap="viridis"), ax=ax, shrink=0.6,
                 label="material depth [mm]")
    ax.set_title(f"cut-away at x = {plane * 1e3:.1f} mm, {run.angles()[step]:.0f} deg: soft "
                 "tissue and patella by material depth, bones grey", fontsize=9)
    save_figure(fig, os.path.join(out, "knee_cutaway.png"), dpi=FIGURE_DPI)


def figure_fold(run, step, out):
    x = run.x[step]
    # All of the skin, framed on the back of the knee: its nodes within 60 mm of the axis centre
    # and behind it (+y is posterior).
    R = camera(-60, 10)
    fig, ax = plt.subplots(figsize=(8, 7))
    draw_surface(ax, x, run.skin_tris(), R, SKIN)
    skin = np.unique(run.skin_tris())
    d = x[skin] - run.center
    back = skin[(np.linalg.norm(d, axis=1) < 0.06) & (d[:, 1] > 0)]
    frame_axes(ax, (x[back] @ R.T)[:, :2], 0.003)
    ax.set_title(f"skin folding at the back of the knee, {run.angles()[step]:.0f} deg "
                 "(posterior-lateral view)")
    save_figure(fig, os.path.join(out, "knee_fold.png"), dpi=FIGURE_DPI)


def patella_path(run):
    """Per step: angle [deg], patella centroid relative to the axis centre (anterior, superior)
    [mm], and path length from the start [mm]. The femur is fixed, so these are femur-relative."""
    ids = run.sets["patella"]
    rows, travelled, previous = [], 0.0, None
    for angle, x in zip(np.concatenate([[0.0], run.angles()]), [run.X] + run.x):
        c = x[ids].mean(axis=0)
        if previous is not None:
            travelled += np.linalg.norm(c - previous)
        previous = c
        d = (c - run.center) * 1e3
        rows.append((angle, -d[1], d[2], travelled * 1e3))
    return np.array(rows)


def figure_patella(run, out):
    rows = patella_path(run)
    with open(os.path.join(out, "knee_patella.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["angle_deg", "anterior_mm", "superior_mm", "travelled_mm"])
        for r in rows:
            w.writerow([f"{r[0]:.2f}", f"{r[1]:.3f}", f"{r[2]:.3f}", f"{r[3]:.3f}"])
    fig, (a, b) = plt.subplots(1, 2, figsize=(11, 5))
    a.plot(rows[:, 1], rows[:, 2], "-o", ms=3)
    for r in rows[::10]:
        a.annotate(f"{r[0]:.0f} deg", (r[1], r[2]), textcoords="offset points", xytext=(5, 3),
                   fontsize=8)
    a.plot([0], [0], "k+")
    a.annotate("flexion axis", (0, 0), textcoords="offset points", xytext=(5, -10), fontsize=8)
    a.set_xlabel("anterior of the axis [mm]")
    a.set_ylabel("superior of the axis [mm]")
    a.set_aspect("equal")
    a.set_title("patella centroid relative to the femur (sagittal)")
    b.plot(rows[:, 0], rows[:, 1], label="anterior")
    b.plot(rows[:, 0], rows[:, 2], label="superior")
    b.plot(rows[:, 0], rows[:, 3], label="distance travelled")
    b.set_xlabel("flexion angle [deg]")
    b.set_ylabel("[mm]")
    b.legend()
    b.set_title("patella against flexion angle")
    fig.tight_layout()
    save_figure(fig, os.path.join(out, "knee_patella.png"), dpi=FIGURE_DPI)
    return rows


def animation(run, out):
    fig, ax = plt.subplots(figsize=(5, 6))
    R = camera(0, 10)
    everything = np.vstack([x @ R.T for x in [run.X] + run.x])[:, :2]
    writer = PillowWriter(fps=8)
    path = os.path.join(out, "knee_flexion.gif")
    try:
        with writer.saving(fig, path, dpi=GIF_DPI):
            for k, x in enumerate([run.X] + run.x):
                ax.clear()
                draw_surface(ax, x, run.skin_tris(), R, SKIN)
                frame_axes(ax, everything)
                angle = 0.0 if k == 0 else run.angles()[k - 1]
                ax.set_title(f"{angle:5.1f} deg")
                writer.grab_frame()
    except OSError as error:
        raise ToolError(f"{path}: cannot write ({error.strerror})") from None
    plt.close(fig)


def main(argv):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("result", help="results file of a knee-flexion run (.h5)")
    parser.add_argument("out", help="folder for the figures (created if missing)")
    parser.add_argument("--step", type=int, help="step shown bent (default: the last)")
    parser.add_argument("--gif", action="store_true", help="also write the animation")
    args = parser.parse_args(argv)
    run = Run(args.result)
    step = len(run.x) - 1 if args.step is None else args.step
    if not 0 <= step < len(run.x):
        raise ToolError(f"{args.result}: no step {step} (steps 0 to {len(run.x) - 1})")
    os.makedirs(args.out, exist_ok=True)
    figure_side(run, step, args.out)
    figure_cutaway(run, step, args.out)
    figure_fold(run, step, args.out)
    rows = figure_patella(run, args.out)
    if args.gif:
        animation(run, args.out)
    print(f"patella: {rows[-1, 3]:.1f} mm travelled by {rows[-1, 0]:.0f} deg")


if __name__ == "__main__":
    run_main(main, sys.argv[1:])
