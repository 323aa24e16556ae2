#!/usr/bin/env python3
"""Draws femreg calibrate's misfit curve: calibration.json -> misfit.png.

    plot_misfit.py DIR/calibration.json DIR/misfit.png
Mean distance of the observed points to the simulated surface (mm) against the fitted
parameter (log axis for a modulus), grid and golden-section samples apart, the fit and its
one-sigma interval marked.
"""
import json
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    with open(sys.argv[1]) as f:
        c = json.load(f)
    samples = sorted(c["samples"], key=lambda s: s["value"])
    modulus = c["parameter"] != "nu"
    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    for stage, style in (("grid", "o"), ("golden", ".")):
        pts = [s for s in samples if s["stage"] == stage]
        ax.plot([s["value"] for s in pts], [s["mean_mm"] for s in pts], style,
                label=f"{stage} samples")
    ax.plot([s["value"] for s in samples], [s["mean_mm"] for s in samples], "-", color="0.6",
            lw=0.8, zorder=0)
    if c.get("usable"):
        ax.axvline(c["value"], color="C3", lw=1,
                   label=f"fit {c['value']:.4g} ({c['misfit_mean_mm']:.2f} mm)")
        lo, hi = c["uncertainty"]["rms_within_10_percent"]
        if lo is not None and hi is not None:
            ax.axvspan(lo, hi, color="C3", alpha=0.12, label="rms within 10 % of best")
    ax.axvline(c["initial_value"], color="0.3", ls="--", lw=1, label="scene's value")
    if modulus:
        ax.set_xscale("log")
    name = {"E": "Young's modulus E (Pa)", "nu": "Poisson ratio",
            "region_E": f"E of region {c.get('region')} (Pa)"}[c["parameter"]]
    ax.set_xlabel(name)
    ax.set_ylabel("mean cloud-to-surface distance (mm)")
    ax.set_title(f"femreg calibrate: {c['object']} ({c['termination']}, "
                 f"{c['evaluations']} forward solves, {c['time_s']:.1f} s)", fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(sys.argv[2], dpi=110)


if __name__ == "__main__":
    main()
