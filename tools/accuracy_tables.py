#!/usr/bin/env python3
"""Markdown tables from femreg bench / compare CSVs (docs/performance/accuracy.md includes them)."""
import csv
import os
import sys


def table(path):
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    name = os.path.basename(path)[:-4]
    out = [f"**{name}**", "",
           "| setting | vertices | ms/frame | seen mm | hidden mm | max mm | Pareto |",
           "|---|---:|---:|---:|---:|---:|:---:|"]
    for r in rows:
        if r.get("error"):
            out.append(f'| {r["setting"]} | | | | | | failed: {r["error"]} |')
            continue
        out.append("| {} | {} | {:.0f} | {:.2f} | {:.2f} | {:.1f} | {} |".format(
            r["setting"], r["vertices"], float(r["median_ms"]), float(r["err_seen_mean_mm"]),
            float(r["err_hidden_mean_mm"]), float(r["err_max_mm"]),
            "*" if r["pareto"] == "1" else ""))
    return "\n".join(out) + "\n"


if __name__ == "__main__":
    print("\n".join(table(p) for p in sys.argv[1:]))
