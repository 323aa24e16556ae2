#!/usr/bin/env python3
"""The forces table (docs/accuracy/forces.md) from tools/forces.sh's runs.

    python3 tools/forces_table.py OUT_DIR

Per dataset and mode: the mean vertex error of the seen and hidden vertices (summary.json),
the median over the frames of the resultant-force error in newtons and in percent of the true
force (the totals row of `femreg eval`'s eval.csv), the median time per frame and the frames
that stopped on their tolerance.
"""
import csv
import json
import os
import sys

DATASETS = ("organ_patch", "hand_press", "tool_table")
MODES = (("classic", "classic"), ("physical", "forces estimated"))


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
    return (f"{float(error['seen_mean']):.2f} / {float(error['hidden_mean']):.2f}",
            f"{float(total['force_error_N']):.3f}", f"{float(total['force_error_pct']):.0f} %",
            f"{float(summary['ms_per_frame_median']):.0f}", f"{converged} / {len(frames)}")


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    out = sys.argv[1]
    print("<!-- written by tools/forces.sh; do not edit by hand -->")
    print("| dataset | mode | seen / hidden mean error (mm) | force error, median (N) | the same, % of the true force | ms per frame (median, 1 thread) | frames converged |")
    print("|---|---|---|---:|---:|---:|---:|")
    for name in DATASETS:
        for mode, label in MODES:
            print(f"| {name} | {label} | " + " | ".join(row(out, name, mode)) + " |")


if __name__ == "__main__":
    main()
