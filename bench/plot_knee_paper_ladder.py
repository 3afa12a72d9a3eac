#!/usr/bin/python3
"""The ladder of bench/knee_paper_ladder.sh as stacked bars, and its table.

    plot_knee_paper_ladder.py LADDER.csv OUT.png [DEGREES]   (the ladder's DEGREES, 3 by default)

Left: seconds per rung (the median over the rounds of each group), stacked by the paper's three
groups and the rest. Right: the same as shares of each rung's time, beside the paper's
63 / 22 / 15 %. Prints the Markdown table of bench/results/knee_paper.md.
"""

import csv
import statistics
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

GROUPS = [("force_stiffness_s", "force/stiffness"), ("collision_s", "collision detection"),
          ("linear_solve_s", "linear solve"), ("other_s", "other")]
PAPER = {"force_stiffness_s": 63.0, "collision_s": 22.0, "linear_solve_s": 15.0, "other_s": 0.0}
COLORS = ["#4c72b0", "#dd8452", "#55a868", "#bbbbbb"]


def main(path, out, degrees="3"):
    rows = list(csv.DictReader(open(path)))
    rungs = sorted({int(r["rung"]) for r in rows})
    names, med = [], []
    for k in rungs:
        mine = [r for r in rows if int(r["rung"]) == k]
        names.append(mine[0]["name"])
        keys = ["wall_s", "newton", "linear"] + [g for g, _ in GROUPS]
        med.append({key: statistics.median(float(r[key]) for r in mine) for key in keys})
        med[-1]["rounds"] = len(mine)
        med[-1]["loaded"] = all(r["loaded"] == "yes" for r in mine)
    print("| rung | change | wall [s] | Newton | linear | force/stiffness | collision | linear solve | other |")
    print("|---|---|---|---|---|---|---|---|---|")
    for k, (name, m) in enumerate(zip(names, med)):
        shares = [100 * m[g] / m["wall_s"] for g, _ in GROUPS]
        print(f"| {k} | {name} | {m['wall_s']:.1f} | {m['newton']:.0f} | {m['linear']:.0f} | "
              + " | ".join(f"{m[g]:.1f} s ({s:.0f} %)" for (g, _), s in zip(GROUPS, shares))
              + " |")
    print("| | the paper (150 degrees, R12000) | 22,560 | | | (63 %) | (22 %) | (15 %) | |")

    fig, (left, right) = plt.subplots(1, 2, figsize=(12, 4.8))
    for axis, percent in ((left, False), (right, True)):
        bars = [str(k) for k in rungs] + ["paper"] if percent else \
            [f"{k}: {n}" for k, n in enumerate(names)]
        bottom = [0.0] * len(bars)
        for (g, label), color in zip(GROUPS, COLORS):
            values = [100 * m[g] / m["wall_s"] if percent else m[g] for m in med]
            if percent:
                values.append(PAPER[g])
            axis.barh(bars, values, left=bottom, color=color, label=label)
            bottom = [b + v for b, v in zip(bottom, values)]
        axis.invert_yaxis()
        axis.set_xlabel("share of the time [%]" if percent else "seconds (median of the rounds)")
    left.legend(loc="lower right", fontsize=8)
    fig.suptitle(f"The knee's first {degrees} degrees: the paper's algorithm to depthfem's default, "
                 "one change per rung")
    fig.tight_layout()
    fig.savefig(out, dpi=110)


if __name__ == "__main__":
    main(*sys.argv[1:])
