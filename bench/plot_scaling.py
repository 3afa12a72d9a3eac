#!/usr/bin/python3
"""Plots the scaling study written by bench/scaling.sh and prints its table.

    /usr/bin/python3 bench/plot_scaling.py bench/results/scaling.csv \
        [--before bench/results/scaling_before.csv] --out bench/results/scaling.png

One row of panels per scene: wall and CPU seconds per Newton iteration, linear iterations per
Newton iteration and peak memory, each against the number of unknowns, one line per solver. The
legends give the exponent p of a least-squares fit t ~ n^p over the sizes that solver completed;
the table's fit rows give it to three places, also over the three largest sizes and against tets.
--before adds the rows of another CSV (the code before a change) as dashed lines.
"""
import argparse
import csv
import math

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def read(path, tag):
    rows = []
    with open(path) as f:
        for r in csv.DictReader(f):
            r["tag"] = tag
            rows.append(r)
    return rows


def exponent(points):
    """Least-squares slope of log t against log n."""
    if len(points) < 2:
        return float("nan")
    xs = [math.log(n) for n, _ in points]
    ys = [math.log(t) for _, t in points]
    mx, my = sum(xs) / len(xs), sum(ys) / len(ys)
    return sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / sum((x - mx) ** 2 for x in xs)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("csv")
    ap.add_argument("--before")
    ap.add_argument("--out", default="bench/results/scaling.png")
    a = ap.parse_args()
    rows = read(a.csv, "")
    if a.before:
        rows += read(a.before, "before")
    scenes = sorted({r["scene"] for r in rows})
    fig, axes = plt.subplots(len(scenes), 4, figsize=(20, 4.5 * len(scenes)), squeeze=False)
    print("| scene | solver | tets | unknowns | Newton it. | linear it. / Newton it. | "
          "s / Newton it. | linear solve s / Newton it. | CPU s / Newton it. | peak MB |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for row_axes, scene in zip(axes, scenes):
        runs = [r for r in rows if r["scene"] == scene]
        for tag, solver in sorted({(r["tag"], r["solver"]) for r in runs}):
            done = sorted((r for r in runs if r["tag"] == tag and r["solver"] == solver
                           and r["success"] == "1"), key=lambda r: int(r["dofs"]))
            if not done:
                continue
            n = [int(r["dofs"]) for r in done]
            t = [float(r["newton_s_per_it"]) for r in done]
            cpu = [float(r["cpu_s_per_it"]) for r in done]
            its = [int(r["linear_iterations"]) / int(r["newton_iterations"]) for r in done]
            mem = [float(r["peak_mb"]) for r in done]
            name = f"{solver} ({tag})" if tag else solver
            style = "--" if tag else "-"
            p, q = exponent(list(zip(n, t))), exponent(list(zip(n, cpu)))
            row_axes[0].loglog(n, t, style + "o", label=f"{name}: n^{p:.2f}")
            row_axes[1].loglog(n, cpu, style + "o", label=f"{name}: n^{q:.2f}")
            row_axes[2].semilogx(n, its, style + "o", label=name)
            row_axes[3].loglog(n, mem, style + "o", label=name)
            for r, k in zip(done, its):
                print(f"| {scene} | {name} | {r['tets']} | {r['dofs']} | {r['newton_iterations']} | "
                      f"{k:.1f} | {float(r['newton_s_per_it']):.3g} | "
                      f"{float(r['linear_s_per_it']):.3g} | {float(r['cpu_s_per_it']):.3g} | "
                      f"{float(r['peak_mb']):.0f} |")
            tets = [int(r["tets"]) for r in done]
            fits = [("fit", n, t, cpu), ("fit, 3 largest", n[-3:], t[-3:], cpu[-3:]),
                    ("fit against tets", tets, t, cpu)]
            for what, x, wall, cpu_time in fits:
                print(f"| {scene} | {name} | {what} | | | | n^{exponent(list(zip(x, wall))):.3f} | | "
                      f"n^{exponent(list(zip(x, cpu_time))):.3f} | |")
        for ax, label in zip(row_axes, ["wall seconds per Newton iteration",
                                        "CPU seconds per Newton iteration",
                                        "linear iterations per Newton iteration",
                                        "peak memory [MB]"]):
            ax.set_xlabel("unknowns")
            ax.set_ylabel(label)
            ax.set_title(scene)
            ax.grid(True, which="both", alpha=0.3)
            ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(a.out, dpi=110)


if __name__ == "__main__":
    main()
