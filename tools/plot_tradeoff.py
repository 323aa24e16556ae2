#!/usr/bin/env python3
"""Plots what accuracy costs in time from femreg bench / compare CSVs.

    python3 tools/plot_tradeoff.py [--compare] --out PLOT.png CSV [CSV ...]

bench: mean vertex error (mm) against median time per frame (ms), one marker per setting,
the Pareto front drawn as a line. compare: seen and hidden vertex error per setting as bars,
with the time per frame written on each. On a recording without ground truth (empty error
columns) the median RMS residual to the cloud takes the error's place. Needs matplotlib
(Debian: python3-matplotlib); femreg runs it with $FEMREG_PYTHON or python3 from PATH.
"""
import argparse
import csv
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def read(path):
    with open(path, newline="") as f:
        rows = [r for r in csv.DictReader(f) if not r.get("error")]
    name = os.path.basename(path).rsplit("_", 1)[0]
    return name, rows


def has_truth(rows):
    return all(r.get("err_mean_mm") for r in rows)


def accuracy(rows, column):
    """The error column, or the RMS residual when the sequence has no ground truth."""
    if has_truth(rows):
        return [float(r[column]) for r in rows], "mean vertex error (mm)"
    return ([float(r["median_rms_residual_mm"]) for r in rows],
            "median RMS residual to the cloud (mm; no ground truth)")


def plot_bench(tables, out):
    fig, axes = plt.subplots(1, len(tables), figsize=(6.5 * len(tables), 5), squeeze=False)
    for ax, (name, rows) in zip(axes[0], tables):
        ms = [float(r["median_ms"]) for r in rows]
        err, ylabel = accuracy(rows, "err_mean_mm")
        front = sorted((m, e) for m, e, r in zip(ms, err, rows) if r["pareto"] == "1")
        ax.scatter(ms, err, color="tab:blue", zorder=3)
        for m, e, r in zip(ms, err, rows):
            ax.annotate(r["setting"], (m, e), textcoords="offset points", xytext=(4, 3), fontsize=7)
        if front:
            ax.plot([p[0] for p in front], [p[1] for p in front], color="tab:red", lw=1.5,
                    zorder=2, label="Pareto front")
            ax.legend(loc="upper right")
        ax.set_xscale("log")
        ax.set_xlabel("median time per frame (ms, log scale)")
        ax.set_ylabel(ylabel)
        ax.set_title(f"{name}: accuracy against time")
        ax.grid(True, which="both", alpha=0.3)
    fig.tight_layout()
    fig.savefig(out, dpi=120)


def plot_compare(tables, out):
    fig, axes = plt.subplots(len(tables), 1, figsize=(10, 4.2 * len(tables)), squeeze=False)
    for ax, (name, rows) in zip(axes[:, 0], tables):
        labels = [r["setting"] for r in rows]
        x = range(len(rows))
        if has_truth(rows):
            seen = [float(r["err_seen_mean_mm"]) for r in rows]
            hidden = [float(r["err_hidden_mean_mm"]) for r in rows]
            ax.bar([i - 0.2 for i in x], seen, width=0.4, label="seen vertices")
            ax.bar([i + 0.2 for i in x], hidden, width=0.4, label="hidden vertices")
            ylabel = "mean vertex error (mm)"
        else:
            seen, ylabel = accuracy(rows, "err_seen_mean_mm")
            hidden = seen
            ax.bar(list(x), seen, width=0.6, label="RMS residual (no ground truth)")
        for i, r in enumerate(rows):
            ax.text(i, max(seen[i], hidden[i]) * 1.02, f'{float(r["median_ms"]):.0f} ms',
                    ha="center", va="bottom", fontsize=7)
        ax.set_xticks(list(x))
        ax.set_xticklabels(labels, rotation=25, ha="right", fontsize=8)
        ax.set_ylabel(ylabel)
        ax.set_yscale("log")
        ax.set_title(f"{name}: regularizers (ms per frame above the bars)")
        ax.legend()
        ax.grid(True, axis="y", which="both", alpha=0.3)
    fig.tight_layout()
    fig.savefig(out, dpi=120)


def main():
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--compare", action="store_true")
    parser.add_argument("--out", required=True)
    parser.add_argument("csv", nargs="+")
    args = parser.parse_args()
    tables = [read(p) for p in args.csv]
    tables = [t for t in tables if t[1]]
    if not tables:
        print("plot_tradeoff.py: no rows to plot", file=sys.stderr)
        return 1
    (plot_compare if args.compare else plot_bench)(tables, args.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
