#!/usr/bin/python3
"""Work-precision diagram from bench_work_precision CSV files: largest tip error against wall
time, one line per integrator (step-size or tolerance ladder), one panel per CSV.

    /usr/bin/python3 bench/plot_work_precision.py bench/results/work_precision.csv [more.csv ...] \
        --out bench/results/work_precision.png [--title "falling_bars" ...]
"""
import argparse
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

STYLE = {  # integrator -> (colour, marker)
    "implicit_euler": ("tab:red", "o"),
    "newmark": ("tab:orange", "s"),
    "symplectic_euler": ("tab:green", "^"),
    "arkode_order2": ("tab:blue", "v"),
    "arkode_order4": ("tab:purple", "D"),
    "arkode_order8": ("tab:brown", "P"),
    "generalized_alpha": ("tab:pink", "X"),
    "arkode_dirk2": ("tab:cyan", "<"),
    "arkode_dirk3": ("tab:olive", ">"),
    "arkode_dirk4": ("tab:gray", "h"),
    "cvode_bdf2": ("black", "*"),
    "cvode_bdf5": ("gold", "p"),
}


def read(path):
    series = {}
    try:
        with open(path, newline="") as f:
            for row in csv.DictReader(f):
                if row["integrator"] == "reference_check" or row["status"] != "ok":
                    continue
                series.setdefault(row["integrator"], []).append(
                    (float(row["wall_s"]), float(row["max_tip_error_m"]), row["setting"], float(row["value"])))
    except (OSError, KeyError, ValueError) as e:
        sys.exit(f"plot_work_precision.py: {path}: cannot read the CSV ({e})")
    if not series:
        sys.exit(f"plot_work_precision.py: {path}: no completed runs")
    return series


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("csv", nargs="+")
    p.add_argument("--out", required=True)
    p.add_argument("--title", action="append", default=[], help="one per CSV, in order")
    a = p.parse_args()
    fig, axes = plt.subplots(1, len(a.csv), figsize=(6.2 * len(a.csv), 4.8), squeeze=False)
    for k, path in enumerate(a.csv):
        ax = axes[0][k]
        for name, pts in read(path).items():
            pts.sort(key=lambda q: -q[3])  # coarse to fine along the ladder
            colour, marker = STYLE.get(name, ("black", "x"))
            ax.loglog([q[0] for q in pts], [q[1] for q in pts], marker=marker, color=colour, label=name)
        ax.set_xlabel("wall time [s]")
        ax.set_ylabel("max error over time [m] (tips, or all nodes)")
        ax.set_title(a.title[k] if k < len(a.title) else path)
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(a.out, dpi=120)
    print(f"wrote {a.out}")


if __name__ == "__main__":
    main()
