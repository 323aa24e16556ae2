#!/usr/bin/env python3
"""The forces table (docs/accuracy/forces.md) and the modes table
(docs/accuracy/physical_mode.md) from tools/forces.sh's runs.

    python3 tools/forces_table.py OUT_DIR [--modes]

Forces table, per dataset with a true force that is not zero on every frame, and mode (OUT_DIR/NAME_classic, NAME_physical and,
where forces.sh ran them, NAME_pushing and NAME_adaptive): the mean vertex error of the seen and
hidden vertices (summary.json), the median over the frames of the resultant-force error in
newtons and in percent of the true force (the totals row of `femreg eval`'s eval.csv), the
median error of the obstacles' push where the dataset has its truth (forces.csv's
contact_force_*_N: hand_press's table), the median time per frame and the frames that stopped
on their tolerance.

--modes: per dataset run (OUT_DIR/NAME_classic and NAME_physical), the two modes side by
side: seen / hidden mean vertex error, median time per frame, frames converged, and the
physical mode's time over the classic one's.
"""
import csv
import json
import os
import sys

# The sequences made for the force estimate first, then the other sequences whose true force
# is not zero on every frame (femreg synth's: a pressing tool, a track without an anchor).
FIRST = ("organ_patch", "hand_press", "tool_table")
MODES = (("classic", "classic"), ("physical", "forces estimated"),
         ("pushing", "forces estimated, pushing only, friction as made"),
         ("adaptive", "forces estimated, adaptive weight"))


def row(out, name, mode):
    run = os.path.join(out, f"{name}_{mode}")
    with open(os.path.join(run, "summary.json")) as f:
        summary = json.load(f)
    with open(os.path.join(run, "eval.csv")) as f:
        total = [r for r in csv.DictReader(f) if r["frame"] == "total"][0]
    with open(os.path.join(run, "stats.csv")) as f:
        frames = list(csv.DictReader(f))
    converged = sum(1 for r in frames if r["termination"] == "converged")
    error = summary["vertex_error_mm"]
    contact = total.get("contact_force_error_N", "")
    return (f"{float(error['seen_mean']):.2f} / {float(error['hidden_mean']):.2f}",
            f"{float(total['force_error_N']):.3f}", f"{float(total['force_error_pct']):.0f} %",
            f"{float(contact):.3f}" if contact else "-",
            f"{float(summary['ms_per_frame_median']):.0f}", f"{converged} / {len(frames)}")


def mode_row(out, name, mode):
    run = os.path.join(out, f"{name}_{mode}")
    with open(os.path.join(run, "summary.json")) as f:
        summary = json.load(f)
    with open(os.path.join(run, "stats.csv")) as f:
        frames = list(csv.DictReader(f))
    converged = sum(1 for r in frames if r["termination"] == "converged")
    error = summary["vertex_error_mm"]
    return (float(error["seen_mean"]), float(error["hidden_mean"]), float(summary["ms_per_frame_median"]),
            converged, len(frames))


def modes(out):
    names = sorted({d.rsplit("_", 1)[0] for d in os.listdir(out)
                    if d.endswith("_classic") and os.path.isdir(os.path.join(out, d))})
    print("<!-- written by tools/forces.sh; do not edit by hand -->")
    print("| dataset | classic: seen / hidden (mm) | ms per frame | converged | forces estimated: seen / hidden (mm) | ms per frame | converged | time, physical over classic |")
    print("|---|---|---:|---:|---|---:|---:|---:|")
    for name in names:
        c = mode_row(out, name, "classic")
        p = mode_row(out, name, "physical")
        ratio = p[2] / c[2] if c[2] > 0 else float("nan")
        print(f"| {name} | {c[0]:.2f} / {c[1]:.2f} | {c[2]:.0f} | {c[3]} / {c[4]} | "
              f"{p[0]:.2f} / {p[1]:.2f} | {p[2]:.0f} | {p[3]} / {p[4]} | {ratio:.1f} |")


def main():
    if len(sys.argv) not in (2, 3) or (len(sys.argv) == 3 and sys.argv[2] != "--modes"):
        sys.exit(__doc__)
    out = sys.argv[1]
    if len(sys.argv) == 3:
        modes(out)
        return
    print("<!-- written by tools/forces.sh; do not edit by hand -->")
    print("| dataset | mode | seen / hidden mean error (mm) | force error, median (N) | the same, % of the true force | the obstacles' push: error, median (N) | ms per frame (median, 1 thread) | frames converged |")
    print("|---|---|---|---:|---:|---:|---:|---:|")
    def has_force(name):
        path = os.path.join(out, f"{name}_physical", "eval.csv")
        if not os.path.exists(path):
            return False
        with open(path) as f:
            total = [r for r in csv.DictReader(f) if r["frame"] == "total"]
        return bool(total) and total[0].get("force_error_pct", "") != ""

    runs = sorted({d.rsplit("_", 1)[0] for d in os.listdir(out)
                   if d.endswith("_physical") and os.path.isdir(os.path.join(out, d))})
    names = [n for n in FIRST if n in runs] + [n for n in runs if n not in FIRST and has_force(n)]
    for name in names:
        for mode, label in MODES:
            if not os.path.isdir(os.path.join(out, f"{name}_{mode}")):
                continue
            print(f"| {name} | {label} | " + " | ".join(row(out, name, mode)) + " |")


if __name__ == "__main__":
    main()
