#!/usr/bin/python3
"""Step-size history from bench_step_sizes: ARKODE's internal step size against time, with the
contact force per output interval on a second axis.

    /usr/bin/python3 bench/plot_step_sizes.py PREFIX [PREFIX ...] --out history.png \
        [--label "order 3, rtol 1e-3" ...]
"""
import argparse
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def read(path, columns):
    try:
        with open(path, newline="") as f:
            rows = list(csv.DictReader(f))
        return [[float(r[c]) for r in rows] for c in columns]
    except (OSError, KeyError, ValueError) as e:
        sys.exit(f"plot_step_sizes.py: {path}: cannot read the CSV ({e})")


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("prefix", nargs="+")
    p.add_argument("--out", required=True)
    p.add_argument("--label", action="append", default=[], help="one per prefix, in order")
    a = p.parse_args()
    fig, ax = plt.subplots(figsize=(8, 4.5))
    force = ax.twinx()
    for k, prefix in enumerate(a.prefix):
        t, h = read(prefix + "_steps.csv", ["time_s", "step_s"])
        ax.semilogy(t, h, ".-", ms=2, lw=0.6, label=a.label[k] if k < len(a.label) else prefix)
        if k == 0:
            ti, f = read(prefix + "_intervals.csv", ["time_s", "contact_force_n"])
            force.plot(ti, f, color="black", lw=0.8, alpha=0.5, label="contact force")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("internal step size [s]")
    force.set_ylabel("contact force, summed magnitudes [N] (grey)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8, loc="lower left")
    fig.tight_layout()
    fig.savefig(a.out, dpi=120)
    print(f"wrote {a.out}")


if __name__ == "__main__":
    main()
