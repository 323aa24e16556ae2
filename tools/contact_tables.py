#!/usr/bin/env python3
"""Markdown tables from tools/contacts.sh's runs: per sequence, collision on against off
(Ceres back end) per frame, and the totals of every run."""
import csv
import json
import sys
from pathlib import Path

out = Path(sys.argv[1])
D_MM = {}


def rows(run):
    with open(out / run / "stats.csv") as f:
        return list(csv.DictReader(f))


def number(r, key):
    v = r.get(key, "")
    return float(v) if v not in ("", None) else float("nan")


for name in ("contact_pair", "tool_table"):
    scene = (out / f"{name}_ceres.yaml").read_text()
    for line in scene.splitlines():
        if line.strip().startswith("distance:"):
            D_MM[name] = 1e3 * float(line.split(":")[1])

print("# Contacts: registered with collision on and off\n")
print("Made by `tools/contacts.sh` (one thread). Vertex errors against the ground truth in mm, "
      "mean over the vertices the camera saw / did not see; gap and penetration from the same "
      "signed gaps of the contacts detected within D at the result: gap = the smallest "
      "(D when none is within D), penetration = max(0, -gap) (docs/theory/contact.md). With "
      "collision off it is measured, not prevented (`femreg register --no-collision`).\n")
for name in ("contact_pair", "tool_table"):
    on, off = rows(f"{name}_ceres_on"), rows(f"{name}_ceres_off")
    print(f"## {name} (D = {D_MM[name]:g} mm, Ceres back end)\n")
    print("| frame | on: seen / hidden (mm) | on: gap (mm) | on: penetration (mm) | contacts | off: seen / hidden (mm) | off: penetration (mm) |")
    print("|---:|---|---:|---:|---:|---|---:|")
    for a, b in zip(on, off):
        print(f"| {a['frame']} | {number(a, 'err_seen_mean_mm'):.2f} / {number(a, 'err_hidden_mean_mm'):.2f} "
              f"| {number(a, 'min_gap_mm'):.2f} | {number(a, 'max_penetration_mm'):.2f} | {a['contacts']} "
              f"| {number(b, 'err_seen_mean_mm'):.2f} / {number(b, 'err_hidden_mean_mm'):.2f} "
              f"| {number(b, 'max_penetration_mm'):.2f} |")
    print()

print("## Totals\n")
print("| sequence | back end | collision | seen mean / max (mm) | hidden mean / max (mm) | deepest penetration (mm) | ms/frame (median) | contact detection ms/frame |")
print("|---|---|---|---|---|---:|---:|---:|")
for name in ("contact_pair", "tool_table"):
    for backend in ("ceres", "fast"):
        for mode in ("on", "off"):
            run = f"{name}_{backend}_{mode}"
            s = json.loads((out / run / "summary.json").read_text())
            e = s["vertex_error_mm"]
            r = rows(run)
            deepest = max(number(x, "max_penetration_mm") for x in r)
            t_coll = sorted(number(x, "t_collision_ms") for x in r)[len(r) // 2]
            print(f"| {name} | {backend} | {mode} | {e['seen_mean']:.2f} / {e['seen_max']:.2f} "
                  f"| {e['hidden_mean']:.2f} / {e['hidden_max']:.2f} | {deepest:.2f} "
                  f"| {s['ms_per_frame_median']:.1f} | {t_coll:.2f} |")
