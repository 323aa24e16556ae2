#!/usr/bin/env python3
"""Compares femreg's forward solve with CalculiX (ccx) on the same meshes and loads.

For every case, femreg_forward_probe solves the problem (linear, corotational, neo-Hookean
with the element or the nodal volume) and writes the displacements and a CalculiX deck
(*ELASTIC or *HYPERELASTIC, NEO HOOKE with the same small-strain moduli; C3D4 on femreg's
mesh, or C3D10 with a node added at every edge's midpoint); ccx solves the deck (linear, or
with NLGEOM); the displacements of femreg's vertices (C3D10's corner nodes) are compared.
Usage:
    compare_calculix.py PROBE [--ccx ccx] [--keep DIR]
"""
import argparse
import csv
import math
import os
import re
import subprocess
import sys
import tempfile

# The comparisons of a case: femreg model, volume, ccx material, ccx element, NLGEOM, label.
HOOKE_RUNS = [
    ("linear", "element", "elastic", "c3d4", 0, "linear vs ccx linear"),
    ("corotational", "element", "elastic", "c3d4", 1, "corotational vs ccx NLGEOM"),
]
NEO_HOOKE_RUNS = [
    ("neo_hookean", "element", "neo_hooke", "c3d4", 1, "neo-Hookean vs ccx NEO HOOKE"),
]
# Near incompressible: the same C3D4 mesh in both (the element form locks in both), and
# the nodal volume and the element form against quadratic C3D10 on that mesh (no locking).
LOCKING_RUNS = [
    ("neo_hookean", "element", "neo_hooke", "c3d4", 1, "neo-Hookean vs ccx NEO HOOKE"),
    ("neo_hookean", "element", "neo_hooke", "c3d10", 1, "NH element vol. vs C3D10 NH"),
    ("neo_hookean", "nodal", "neo_hooke", "c3d10", 1, "NH nodal volume vs C3D10 NH"),
    ("corotational", "element", "elastic", "c3d10", 1, "corotational vs C3D10 NLGEOM"),
]

# name, probe arguments, femreg load steps for the nonlinear runs, runs
CASES = [
    ("beam 1k, gravity (E=1e8)", "shape=box n=4 length=1 height=0.1 E=1e8 nu=0.3 gravity=9.81", 1,
     HOOKE_RUNS),
    ("beam 1k, small tip 0.025 N", "shape=box n=4 length=1 height=0.1 E=1e6 nu=0.3 tip_load=0.025", 1,
     HOOKE_RUNS),
    ("beam 1k, large tip 16 N", "shape=box n=4 length=1 height=0.1 E=1e6 nu=0.3 tip_load=16", 8,
     HOOKE_RUNS + NEO_HOOKE_RUNS),
    ("soft cylinder, gravity (E=1e6)",
     "shape=cylinder n=3 radius=0.05 length=0.5 axial=20 E=1e6 nu=0.35 gravity=9.81", 4,
     HOOKE_RUNS + NEO_HOOKE_RUNS),
    # What quadratic elements gain in bending at nu 0.3 (no locking): the reference for the
    # nu 0.49 rows below.
    ("beam 1k, gravity (E=1e8)", "shape=box n=4 length=1 height=0.1 E=1e8 nu=0.3 gravity=9.81", 1,
     [("corotational", "element", "elastic", "c3d10", 1, "corotational vs C3D10 NLGEOM")]),
    ("beam 1k, gravity, nu 0.49 (E=1e8)", "shape=box n=4 length=1 height=0.1 E=1e8 nu=0.49 gravity=9.81",
     1, LOCKING_RUNS),
    ("soft cylinder, gravity, nu 0.49 (E=3e5)",
     "shape=cylinder n=3 radius=0.05 length=0.5 axial=20 E=3e5 nu=0.49 gravity=9.81", 4, LOCKING_RUNS),
]


def read_probe_csv(path):
    ids, rest, u, tip = [], [], [], []
    with open(path) as f:
        for row in csv.DictReader(f):
            ids.append(int(row["id"]))
            rest.append((float(row["X"]), float(row["Y"]), float(row["Z"])))
            u.append((float(row["ux"]), float(row["uy"]), float(row["uz"])))
            tip.append(row["tip"] == "1")
    return ids, rest, u, tip


def read_ccx_dat(path):
    """The last 'displacements' block of a .dat file: {node: (ux, uy, uz)}."""
    blocks, current = [], None
    with open(path) as f:
        for line in f:
            if "displacements" in line:
                current = {}
                blocks.append(current)
                continue
            parts = line.split()
            if current is not None and len(parts) == 4:
                try:
                    current[int(parts[0])] = tuple(float(p) for p in parts[1:])
                except ValueError:
                    current = None
            elif current is not None and parts:
                current = None
    if not blocks:
        raise RuntimeError(f"no displacements in {path}")
    return blocks[-1]


def norm(v):
    return math.sqrt(sum(c * c for c in v))


def run(cmd, cwd, log):
    with open(log, "w") as out:
        subprocess.run(cmd, cwd=cwd, stdout=out, stderr=subprocess.STDOUT, check=True)


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("probe")
    parser.add_argument("--ccx", default="ccx")
    parser.add_argument("--keep", default=None, help="keep the decks and results in DIR")
    args = parser.parse_args()
    args.probe = os.path.abspath(args.probe)  # the probe runs in the work folder
    work = args.keep or tempfile.mkdtemp(prefix="femreg_ccx_")
    os.makedirs(work, exist_ok=True)

    header = (f"{'case':40s} {'model':30s} {'nodes':>6s} {'max|u| femreg':>14s} {'max|u| ccx':>12s}"
              f" {'tip femreg':>12s} {'tip ccx':>12s} {'tip rel':>9s} {'max|du|/max|u|':>15s}"
              f" {'femreg its':>10s}")
    print(header)
    print("-" * len(header))
    for index, (name, probe_args, steps, runs) in enumerate(CASES):
        for run_index, (femreg_model, volume, ccx_material, element, nlgeom, label) in enumerate(runs):
            stem = f"case{index}_{run_index}_{femreg_model}"
            csv_path = os.path.join(work, stem + ".csv")
            cmd = [args.probe] + probe_args.split() + [
                f"model={femreg_model}", f"volume={volume}", f"load_steps={steps if nlgeom else 1}",
                f"csv={csv_path}", f"inp={os.path.join(work, stem + '.inp')}", f"nlgeom={nlgeom}",
                f"ccx_material={ccx_material}", f"element={element}"]
            probe_log = os.path.join(work, stem + ".probe.log")
            run(cmd, work, probe_log)
            # Newton iterations over all load steps, from the probe's brief report.
            found = re.search(r"(\d+) Newton iterations", open(probe_log).read())
            iterations = found.group(1) if found else "?"
            run([args.ccx, "-i", stem], work, os.path.join(work, stem + ".ccx.log"))
            ids, _, uf, tip = read_probe_csv(csv_path)
            uc_map = read_ccx_dat(os.path.join(work, stem + ".dat"))
            uc = [uc_map[i] for i in ids]
            max_f = max(norm(u) for u in uf)
            max_c = max(norm(u) for u in uc)
            max_diff = max(norm([a - b for a, b in zip(p, q)]) for p, q in zip(uf, uc))
            tip_ids = [k for k, t in enumerate(tip) if t]
            tip_f = [sum(uf[k][c] for k in tip_ids) / len(tip_ids) for c in range(3)]
            tip_c = [sum(uc[k][c] for k in tip_ids) / len(tip_ids) for c in range(3)]
            tip_rel = norm([a - b for a, b in zip(tip_f, tip_c)]) / norm(tip_c)
            print(f"{name:40s} {label:30s} {len(ids):6d} {max_f:14.6e} {max_c:12.6e}"
                  f" {norm(tip_f):12.6e} {norm(tip_c):12.6e} {tip_rel:9.2e} {max_diff / max_c:15.2e}"
                  f" {iterations:>10s}")
            sys.stdout.flush()
    print(f"\n(decks and results in {work}; ccx prints 7 significant digits, so ~1e-6 is the floor)")


if __name__ == "__main__":
    main()
