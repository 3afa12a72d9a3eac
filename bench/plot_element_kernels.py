#!/usr/bin/python3
"""Plots the element-kernel layout study written by bench_element_kernels (Google Benchmark JSON).

Left: roofline per core. The ceilings are the measured fused multiply-add peak and memory
bandwidth (Ceiling/* benchmarks); each kernel sits at its arithmetic intensity (flops per tet over
the bytes a tet cannot avoid moving) and its measured rate on one thread. Right: tets per second
per core for every layout x kernel x order, on 1 and 2 threads, with the roofline bound of each
order drawn as a line. Rates are per CPU-second of the process; of repeated runs
(--benchmark_repetitions) the fastest is drawn.

    /usr/bin/python3 bench/plot_element_kernels.py bench/results/element_kernels.json \\
        --out bench/results/element_kernels.png [--table]

--table also prints the rates as the Markdown table of bench/results/element_kernels.md.
"""
import argparse
import json
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

ORDERS = ["Energy", "Gradient", "Hessian"]
KERNELS = ["scalar", "batched", "batched_w4", "batched_stdsimd"]
# One color per layout x kernel: greys for the scalar kernel, a hue per layout for the batched one.
GROUP_COLORS = {("AoS", "scalar"): "#d9d9d9", ("SoA", "scalar"): "#a6a6a6",
                ("AoSoA", "scalar"): "#737373", ("AoS", "batched"): "#fdae6b",
                ("SoA", "batched"): "#3182bd", ("AoSoA", "batched"): "#31a354",
                ("SoA", "batched_w4"): "#9ecae1", ("SoA", "batched_stdsimd"): "#de2d26",
                ("SoA", "assembly"): "#67000d"}
LAYOUT_MARKERS = {"AoS": "o", "SoA": "s", "AoSoA": "^"}


RATES = ("per_core", "flops_per_s_per_core", "bytes_per_s_per_core")


def load(path):
    """Runs by name (tuple of its parts, thread counts as ints); of repeated runs the fastest."""
    with open(path) as f:
        data = json.load(f)
    runs = {}
    for b in data["benchmarks"]:
        if b.get("run_type", "iteration") != "iteration":
            continue
        parts = [p for p in b["run_name"].split("/") if p not in ("process_time", "real_time")]
        key = tuple(int(p) if p.isdigit() else p for p in parts)
        rate = next(b[c] for c in RATES if c in b)
        if key not in runs or rate > next(runs[key][c] for c in RATES if c in runs[key]):
            runs[key] = b
    return data.get("context", {}), runs


def threads_of(key):
    return next(k for k in key if isinstance(k, int))


def print_table(runs, groups, peak, bandwidth):
    """Million tets per CPU-second per core, 1 and 2 threads, per order, as Markdown."""
    print("| layout | kernel | " + " | ".join(f"{o} 1 thr | {o} 2 thr" for o in ORDERS) + " |")
    print("|---|---|" + "---|---|" * len(ORDERS))
    for layout, kind in groups:
        cells = []
        for order in ORDERS:
            for t in (1, 2):
                key = ("Kernel", layout, kind, order, t)
                cells.append(f"{runs[key]['per_core'] / 1e6:.1f}" if key in runs else "")
        print(f"| {layout} | {kind} | " + " | ".join(cells) + " |")
    bounds = []
    for order in ORDERS:
        r = runs[("Kernel", "SoA", "batched", order, 1)]
        bounds += [f"{min(peak / r['flops_per_tet'], bandwidth[t] / r['bytes_per_tet']) / 1e6:.0f}"
                   for t in (1, 2)]
    print("| bound | | " + " | ".join(bounds) + " |")


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("json")
    parser.add_argument("--out", required=True)
    parser.add_argument("--table", action="store_true")
    args = parser.parse_args()
    context, runs = load(args.json)
    # The production path (Elasticity::evaluate: SoA, batched, scatter) as a kernel of its own.
    for key in [k for k in runs if k[0] == "Assembly"]:
        runs[("Kernel", "SoA", "assembly", key[1], key[2])] = runs[key]

    def ceiling(name, counter, *args):
        key = ("Ceiling", name, *args)
        if key not in runs and len(args) == 2:
            key = key[:-1]  # a record from before the triad's array size was an argument
        if key not in runs:
            sys.exit(f"{args.json}: no {'/'.join(map(str, key))} run")
        return runs[key][counter]

    peak = ceiling("PeakFlops", "flops_per_s_per_core", 1)
    # The kernels' data fits the last-level cache: the ceiling of the 32 MiB arrays (2^22 entries).
    bandwidth = {t: ceiling("Bandwidth", "bytes_per_s_per_core", t, 22) for t in (1, 2)}

    kernels = [k for k in runs if k[0] == "Kernel" and k[2] != "assembly"]
    layouts = [l for l in LAYOUT_MARKERS if any(k[1] == l for k in kernels)]
    kinds = [c for c in KERNELS if any(k[2] == c for k in kernels)]

    fig, (roof, bars) = plt.subplots(1, 2, figsize=(15, 6), gridspec_kw={"width_ratios": [1, 1.6]})

    # Roofline (one thread).
    intensities = [runs[k]["flops_per_tet"] / runs[k]["bytes_per_tet"] for k in runs
                   if k[0] in ("Kernel", "Assembly")]
    lo, hi = min(intensities) / 3, max(intensities) * 3
    xs = [lo * (hi / lo) ** (i / 100) for i in range(101)]
    roof.loglog(xs, [min(peak, x * bandwidth[1]) / 1e9 for x in xs], "k-", lw=1.5,
                label=f"bound: {peak / 1e9:.0f} GFLOP/s, {bandwidth[1] / 1e9:.0f} GB/s per core")
    for key in kernels:
        if threads_of(key) != 1:
            continue
        r = runs[key]
        roof.loglog(r["flops_per_tet"] / r["bytes_per_tet"], r["flops_per_tet"] * r["per_core"] / 1e9,
                    LAYOUT_MARKERS[key[1]], color=GROUP_COLORS[key[1:3]], ms=8, mec="k", mew=0.6)
    for key in runs:
        if key[0] == "Assembly" and threads_of(key) == 1:
            r = runs[key]
            roof.loglog(r["flops_per_tet"] / r["bytes_per_tet"],
                        r["flops_per_tet"] * r["per_core"] / 1e9, "D", color="#d62728", ms=7)
            roof.annotate(f"assembly: {key[1].lower()}", (r["flops_per_tet"] / r["bytes_per_tet"],
                          r["flops_per_tet"] * r["per_core"] / 1e9), textcoords="offset points",
                          xytext=(6, -12), fontsize=8)
    for l in layouts:
        roof.plot([], [], LAYOUT_MARKERS[l], color="w", mec="k", label=l)
    roof.set_xlabel("arithmetic intensity [flop/byte]")
    roof.set_ylabel("GFLOP/s per core (one thread)")
    roof.set_title("roofline: energy, gradient, Hessian (left to right)")
    roof.grid(True, which="both", alpha=0.3)
    roof.legend(fontsize=8, loc="lower right")

    # Throughput bars.
    groups = [(l, k) for l in layouts for k in kinds if any(key[1:3] == (l, k) for key in kernels)]
    groups.append(("SoA", "assembly"))
    width = 0.8 / len(groups)
    for g, (layout, kind) in enumerate(groups):
        for t, hatch in ((1, None), (2, "//")):
            heights = []
            for order in ORDERS:
                key = ("Kernel", layout, kind, order, t)
                heights.append(runs[key]["per_core"] / 1e6 if key in runs else 0)
            x = [i + (g - len(groups) / 2 + 0.5) * width + (0.0 if t == 1 else width * 0.45)
                 for i in range(len(ORDERS))]
            bars.bar(x, heights, width * 0.45, color=GROUP_COLORS[(layout, kind)], hatch=hatch,
                     edgecolor="k", lw=0.4, label=f"{layout} {kind}" if t == 1 else None)
    for i, order in enumerate(ORDERS):
        r = runs[("Kernel", "SoA", "batched", order, 1)]
        bound = min(peak / r["flops_per_tet"], bandwidth[1] / r["bytes_per_tet"]) / 1e6
        bars.hlines(bound, i - 0.45, i + 0.45, colors="k", linestyles="--", lw=1)
        bars.annotate(f"bound {bound:.0f} M", (i, bound), textcoords="offset points",
                      xytext=(0, 3), ha="center", fontsize=8)
    bars.set_yscale("log")
    bars.set_xticks(range(len(ORDERS)), [f"{o}\n({runs[('Kernel', 'SoA', 'batched', o, 1)]['flops_per_tet']:.0f} flop, "
                                         f"{runs[('Kernel', 'SoA', 'batched', o, 1)]['bytes_per_tet']:.0f} B per tet)"
                                         for o in ORDERS])
    bars.set_ylabel("million tets per second per core (hatched: 2 threads)")
    bars.set_title("layout x kernel x order")
    bars.grid(True, axis="y", which="both", alpha=0.3)
    bars.legend(fontsize=7, ncol=3, loc="lower left")
    if args.table:
        print_table(runs, groups, peak, bandwidth)
    fig.suptitle(f"Mooney-Rivlin tet kernels, 192,000 tets "
                 f"({context.get('num_cpus', '?')} CPUs, {context.get('mhz_per_cpu', '?')} MHz)")
    fig.tight_layout()
    fig.savefig(args.out, dpi=110)


if __name__ == "__main__":
    main()
