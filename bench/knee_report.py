#!/usr/bin/python3
"""Figures of a knee-flexion run beside the paper's (section 6), for bench/knee_flexion.sh.

    knee_report.py RESULT.h5 RUN.log OUT_PREFIX

Writes OUT_PREFIX_steps.csv, OUT_PREFIX_timing.csv and OUT_PREFIX.md (see knee_flexion.sh).
The timing groups and the wall time come from the run's timing table in RUN.log; a run killed
before printing it falls back to the /timing of the results file (rewritten after every step)
and the sum of the step times.
"""

import csv
import os
import re
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "apps", "tools"))
from results import Results  # noqa: E402

# The paper: 376 minutes on one 300 MHz R12000; 63 % force and stiffness, 22 % collision
# detection (tree construction under 1 %), 15 % linear solve.
PAPER_MINUTES = 376.0
PAPER_SHARE = {"force/stiffness": 63.0, "collision detection": 22.0, "linear solve": 15.0,
               "other": 0.0}
GROUPS = ("force/stiffness", "collision detection", "linear solve")


def groups_from_log(path):
    """{group: seconds} and the wall time from the '= group' lines of the timing table."""
    try:
        text = open(path, encoding="utf-8", errors="replace").read()
    except OSError:
        return None, None
    wall = re.search(r"timing \(s, share of ([0-9.]+) s wall\)", text)
    found = dict(re.findall(r"^  = (\S.*?)\s+([0-9.]+)\s+[0-9.]+ %$", text, re.M))
    if not wall or not found:
        return None, None
    return {k: float(v) for k, v in found.items()}, float(wall.group(1))


def main(result, log, prefix):
    with Results(result) as r:
        scene = r.scene()
        status = r.status
        missing = np.full(r.num_steps, np.nan)
        rows = np.column_stack([
            r.series("load"), r.series("newton_iterations"), r.series("seconds"),
            r.series("penetration") if r.has("penetration") else missing,
            r.series("contact_area") if r.has("contact_area") else missing])
        phases = r.timing()
    total_angle = next(b["angle_deg"] for b in scene["boundary"] if b["type"] == "rotated")
    rows = np.array(rows, float).reshape(-1, 5)
    with open(prefix + "_steps.csv", "w", newline="") as out:
        w = csv.writer(out)
        w.writerow(["step", "angle_deg", "newton_iterations", "seconds", "penetration_mm",
                    "contact_area_cm2"])
        for k, (load, newton, seconds, depth, area) in enumerate(rows):
            w.writerow([k, f"{load * total_angle:.3f}", int(newton), f"{seconds:.2f}",
                        f"{depth * 1e3:.4f}", f"{area * 1e4:.3f}"])

    groups, wall = groups_from_log(log)
    if groups is None:  # killed: what the results file kept
        groups = {g: sum(v for k, v in phases.items() if k.startswith(g)) for g in GROUPS}
        wall = float(rows[:, 2].sum())
        groups["other"] = wall - sum(groups.values())
    with open(prefix + "_timing.csv", "w", newline="") as out:
        w = csv.writer(out)
        w.writerow(["group", "seconds", "share_percent", "paper_share_percent"])
        for g in GROUPS + ("other",):
            w.writerow([g, f"{groups[g]:.1f}", f"{100 * groups[g] / wall:.1f}", PAPER_SHARE[g]])

    angle = rows[-1, 0] * total_angle if len(rows) else 0.0
    newton = rows[:, 1]
    lines = [
        f"{scene.get('name', '?')}: {status}, {len(rows)} steps to {angle:.1f} deg, "
        f"wall {wall:.1f} s ({wall / 60:.1f} min), speed-up over the paper's "
        f"{PAPER_MINUTES:.0f} min: {PAPER_MINUTES * 60 / wall:.1f}x",
        "",
        f"Newton iterations per step: mean {newton.mean():.2f}, max {int(newton.max())}; "
        f"deepest penetration {np.nanmax(rows[:, 3]) * 1e3:.3f} mm",
        "",
        "| group | seconds | share | paper's share |",
        "|---|---|---|---|",
    ]
    for g in GROUPS + ("other",):
        lines.append(f"| {g} | {groups[g]:.1f} | {100 * groups[g] / wall:.1f} % | "
                     f"{PAPER_SHARE[g]:.0f} % |")
    lines.append(f"| total | {wall:.1f} | 100 % | 100 % ({PAPER_MINUTES:.0f} min) |")
    with open(prefix + ".md", "w") as out:
        out.write("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    if len(sys.argv) != 4:
        sys.exit("usage: knee_report.py RESULT.h5 RUN.log OUT_PREFIX")
    main(*sys.argv[1:])
