#!/usr/bin/env python3
"""Compares femreg's forward solve with CalculiX (ccx) on the same meshes and loads.

For every case, femreg_forward_probe solves the problem (linear, corotational, neo-Hookean
with the element or the nodal volume) and writes the displacements and a CalculiX deck
(*ELASTIC or *HYPERELASTIC, NEO HOOKE with the same small-strain moduli; C3D4 on femreg's
mesh, or C3D10 with a node added at every edge's midpoint); ccx solves the deck (linear, or
with NLGEOM); the displacements of femreg's vertices (C3D10's corner nodes) are compared.
Contact (tools/press_case.h): a soft block pressed onto a clamped soft block or onto a rigid
plane (in ccx: the same block with every node held), frictionless and with Coulomb friction,
pressed and then slid; ccx solves *CONTACT PAIR, surface to surface, with a linear penalty and
NLGEOM on the same C3D4 meshes. Compared: the total contact force on the pressed block (femreg's
ContactPotential::Forces; ccx's: minus the reaction at the pressed face) and the displacements
of the pressed block's free surface (its sides).
Separation (tools/cut_case.h): a soft beam bent by a gripper, then a 5 mm slab of its elements
removed (ccx: *MODEL CHANGE, TYPE=ELEMENT, REMOVE in a second NLGEOM step; femreg: the elements
dropped from the mesh) while the gripper carries the free end on. Compared: every node's
displacement after each step, per piece after the cut.
Usage:
    compare_calculix.py PROBE [--ccx ccx] [--keep DIR] [--only single|contact|cut]
                        [--markdown FILE] [--fixture DIR]
--markdown writes the contact table, --fixture ccx's forces and displacements for
tests/contact_press_test.cc (tests/fixtures/calculix_contact).
"""
import argparse
import csv
import math
import os
import re
import subprocess
import sys
import tempfile
import time

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

# Contact: name, probe arguments (shape=press). The pressed block's top face moves 1.5 mm down
# (the gap is 0.5 mm), then 3 mm along x.
CONTACT_CASES = [
    ("block on block, frictionless", "support=block"),
    ("block on block, mu 0.3, pressed", "support=block mu=0.3"),
    ("block on block, mu 0.3, slid 3 mm", "support=block mu=0.3 slide=0.003"),
    ("block on rigid plane, frictionless", "support=plane"),
    ("block on rigid plane, mu 0.3, slid 3 mm", "support=plane mu=0.3 slide=0.003"),
]
# Against the plane the pressed block is compressed 1 mm of its 2 cm (5 %) above. Pressed
# 3 mm (15 %), the two neo-Hookean laws (femreg's stable one, ccx's with J^(-2/3)) part, and the
# corotational element against *ELASTIC, which NLGEOM makes St. Venant-Kirchhoff (softer in
# compression), parts further.
CONTACT_LAW_CASES = [
    ("block on rigid plane, corotational", "support=plane model=corotational"),
    ("block on block, pressed 3 mm", "support=block press=0.0035"),
    ("block on rigid plane, pressed 3 mm", "support=plane press=0.0035"),
    ("block on rigid plane, 3 mm, corotational", "support=plane press=0.0035 model=corotational"),
]


# The cut (issue 43): name, probe arguments (shape=cut; tools/cut_case.h). The beam (200 x 30 x
# 30 mm, 40 x 6 x 6 cells, E 50 kPa) is bent by its gripper, then the 70-75 mm slab's elements
# are removed while the gripper carries the free end on by (16, 0, 12) mm.
CUT_CASES = [
    ("beam bent 0.2 rad, then cut", "bend=0.2"),
    ("beam bent 0.4 rad, then cut", "bend=0.4"),
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


def read_ccx_totals(path, node_set):
    """The last 'total force' line of node_set in a .dat file: (fx, fy, fz)."""
    found, want = None, False
    with open(path) as f:
        for line in f:
            if "total force" in line:
                want = f"SET {node_set.upper()} " in line.upper()
                continue
            parts = line.split()
            if want and len(parts) == 3:
                found = tuple(float(p) for p in parts)
                want = False
    if found is None:
        raise RuntimeError(f"no total force of {node_set} in {path}")
    return found


def read_press_csv(path):
    rows = {}
    with open(path) as f:
        for row in csv.DictReader(f):
            rows[int(row["id"])] = ((float(row["ux"]), float(row["uy"]), float(row["uz"])), row["free"] == "1")
    return rows


def read_forces(path):
    with open(path) as f:
        return {row["quantity"]: (float(row["fx"]), float(row["fy"]), float(row["fz"]))
                for row in csv.DictReader(f)}


def contact_cases(args, work):
    """Runs the contact cases; returns the table's rows."""
    header = (f"{'case':42s} {'F femreg (x, z) N':>20s} {'F ccx (x, z) N':>20s} {'|dF|/|F|':>9s}"
              f" {'u rms rel':>9s} {'u max rel':>9s} {'pen. mm':>8s} {'its':>5s} {'ccx s':>6s}")
    print(header)
    print("-" * len(header))
    rows = []
    for index, (name, probe_args) in enumerate(CONTACT_CASES + CONTACT_LAW_CASES):
        stem = f"press{index}"
        csv_path, forces_path = os.path.join(work, stem + ".csv"), os.path.join(work, stem + "_forces.csv")
        cmd = [args.probe, "shape=press"] + probe_args.split() + [
            f"csv={csv_path}", f"forces={forces_path}", f"inp={os.path.join(work, stem + '.inp')}"]
        probe_log = os.path.join(work, stem + ".probe.log")
        run(cmd, work, probe_log)
        log = open(probe_log).read()
        found = re.search(r"press: .*?(\d+) Newton iterations", log)
        iterations = found.group(1) if found else "?"
        found = re.search(r"deepest penetration ([-0-9.e+]+) mm", log)
        penetration = float(found.group(1)) if found else float("nan")
        start = time.time()
        run([args.ccx, "-i", stem], work, os.path.join(work, stem + ".ccx.log"))
        ccx_seconds = time.time() - start
        femreg_u = read_press_csv(csv_path)
        dat = os.path.join(work, stem + ".dat")
        ccx_u = read_ccx_dat(dat)
        # The support's force on the pressed block: minus the reaction at its pressed face.
        ccx_force = tuple(-c for c in read_ccx_totals(dat, "Ntop"))
        femreg_force = read_forces(forces_path)["contact"]
        force_rel = norm([a - b for a, b in zip(femreg_force, ccx_force)]) / norm(ccx_force)
        free = [i for i, (_, is_free) in femreg_u.items() if is_free]
        diff = [norm([a - b for a, b in zip(femreg_u[i][0], ccx_u[i])]) for i in free]
        size = [norm(ccx_u[i]) for i in free]
        rms_rel = math.sqrt(sum(d * d for d in diff) / sum(c * c for c in size))
        max_rel = max(diff) / max(size)
        print(f"{name:42s} {femreg_force[0]:9.4f} {femreg_force[2]:10.4f} {ccx_force[0]:9.4f}"
              f" {ccx_force[2]:10.4f} {force_rel:9.2%} {rms_rel:9.2%} {max_rel:9.2%}"
              f" {penetration:8.4f} {iterations:>5s} {ccx_seconds:6.1f}")
        sys.stdout.flush()
        rows.append((name, probe_args, femreg_force, ccx_force, force_rel, rms_rel, max_rel, penetration,
                     iterations, ccx_seconds, ccx_u))
    return rows


def fortran_float(text):
    """A number as ccx prints it: a three-digit exponent loses its E (-1.016177-120)."""
    try:
        return float(text)
    except ValueError:
        return float(re.sub(r"(?<=[0-9.])([-+])(\d{3})$", r"E\1\2", text))


def read_ccx_steps(path):
    """The last 'displacements' block of each step of a .dat file, by the time it prints
    (step 1 ends at time 1, step 2 at 2): [{node: (ux, uy, uz)}, ...]."""
    blocks, current = {}, None
    with open(path) as f:
        for line in f:
            if "displacements" in line:
                found = re.search(r"time\s+([-0-9.E+]+)", line)
                current = {}
                blocks[float(found.group(1)) if found else len(blocks)] = current
                continue
            parts = line.split()
            if current is not None and len(parts) == 4:
                try:
                    current[int(parts[0])] = tuple(fortran_float(p) for p in parts[1:])
                except ValueError:
                    current = None
            elif current is not None and parts:
                current = None
    ends = []
    for step in (1.0, 2.0):
        at = [t for t in blocks if abs(t - step) < 1e-6]
        if not at:
            raise RuntimeError(f"no displacements at the end of step {step:g} in {path}")
        ends.append(blocks[at[0]])
    return ends


def read_cut_csv(path):
    rows = {}
    with open(path) as f:
        for row in csv.DictReader(f):
            rows[int(row["id"])] = ((float(row["ux1"]), float(row["uy1"]), float(row["uz1"])),
                                    (float(row["ux2"]), float(row["uy2"]), float(row["uz2"])),
                                    int(row["piece"]))
    return rows


def cut_cases(args, work):
    """The beam bent, then a slab of its elements removed (*MODEL CHANGE, TYPE=ELEMENT,
    REMOVE): the displacements after each step, per piece after the cut."""
    header = (f"{'case':34s} {'step':16s} {'nodes':>6s} {'max|u| femreg':>14s} {'max|u| ccx':>12s}"
              f" {'rms|du|/max|u|':>9s} {'max|du|/max|u|':>9s} {'its':>5s} {'ccx s':>6s}")
    print(header)
    print("-" * len(header))
    rows = []
    for index, (name, probe_args) in enumerate(CUT_CASES):
        stem = f"cut{index}"
        csv_path = os.path.join(work, stem + ".csv")
        cmd = [args.probe, "shape=cut"] + probe_args.split() + [
            f"csv={csv_path}", f"inp={os.path.join(work, stem + '.inp')}"]
        probe_log = os.path.join(work, stem + ".probe.log")
        run(cmd, work, probe_log)
        found = re.search(r"cut: .*?(\d+) Newton iterations", open(probe_log).read())
        iterations = found.group(1) if found else "?"
        start = time.time()
        run([args.ccx, "-i", stem], work, os.path.join(work, stem + ".ccx.log"))
        ccx_seconds = time.time() - start
        femreg_u = read_cut_csv(csv_path)
        ccx_steps = read_ccx_steps(os.path.join(work, stem + ".dat"))
        # Relative to the step's largest ccx displacement (the clamped piece is back at rest
        # after the cut: its own displacements are ~0).
        step_max = [max(norm(u) for u in ccx_steps[k].values()) for k in range(2)]
        for step, label, nodes in ((0, "bent (intact)", [i for i in femreg_u]),
                                   (1, "cut, clamped", [i for i, r in femreg_u.items() if r[2] == 0]),
                                   (1, "cut, free", [i for i, r in femreg_u.items() if r[2] == 1])):
            uf = [femreg_u[i][step] for i in nodes]
            uc = [ccx_steps[step][i] for i in nodes]
            diff = [norm([a - b for a, b in zip(p, q)]) for p, q in zip(uf, uc)]
            rms_rel = math.sqrt(sum(d * d for d in diff) / len(diff)) / step_max[step]
            max_rel = max(diff) / step_max[step]
            print(f"{name:34s} {label:16s} {len(nodes):6d} {max(norm(u) for u in uf):14.6e}"
                  f" {max(norm(u) for u in uc):12.6e} {rms_rel:9.2%} {max_rel:9.2%} {iterations:>5s}"
                  f" {ccx_seconds:6.1f}")
            rows.append((name, label, len(nodes), max(diff), step_max[step], rms_rel, max_rel))
        sys.stdout.flush()
    return rows


def write_markdown(path, rows):
    with open(path, "w") as out:
        out.write("| case | contact force femreg (x, z) N | ccx (x, z) N | force error | displacement"
                  " error, rms / max | femreg penetration (mm) | Newton its | ccx (s) |\n")
        out.write("|---|---|---|---|---|---|---|---|\n")
        for name, _, f, c, force_rel, rms_rel, max_rel, pen, its, seconds, _ in rows:
            out.write(f"| {name} | {f[0]:.4f}, {f[2]:.4f} | {c[0]:.4f}, {c[2]:.4f} | {force_rel:.2%} |"
                      f" {rms_rel:.2%} / {max_rel:.2%} | {pen:.4f} | {its} | {seconds:.0f} |\n")


def write_fixture(directory, rows):
    """ccx's results for tests/contact_press_test.cc: the cases' forces, each case's displacements."""
    os.makedirs(directory, exist_ok=True)
    with open(os.path.join(directory, "cases.csv"), "w") as out:
        out.write("case,args,fx,fy,fz\n")
        for index, (_, probe_args, _, c, *_rest) in enumerate(rows[:len(CONTACT_CASES)]):
            out.write(f"press{index},{probe_args},{c[0]:.7g},{c[1]:.7g},{c[2]:.7g}\n")
    for index, row in enumerate(rows[:len(CONTACT_CASES)]):
        with open(os.path.join(directory, f"press{index}_u.csv"), "w") as out:
            out.write("id,ux,uy,uz\n")
            for node, u in sorted(row[-1].items()):
                out.write(f"{node},{u[0]:.7g},{u[1]:.7g},{u[2]:.7g}\n")


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
    parser.add_argument("--only", choices=["single", "contact", "cut"], default=None)
    parser.add_argument("--markdown", default=None, help="write the contact table to FILE")
    parser.add_argument("--fixture", default=None, help="write ccx's contact results to DIR")
    args = parser.parse_args()
    args.probe = os.path.abspath(args.probe)  # the probe runs in the work folder
    work = args.keep or tempfile.mkdtemp(prefix="femreg_ccx_")
    os.makedirs(work, exist_ok=True)

    if args.only in (None, "cut"):
        cut_cases(args, work)
        if args.only == "cut":
            print(f"\n(decks and results in {work})")
            return
        print()

    if args.only != "single":
        rows = contact_cases(args, work)
        if args.markdown:
            write_markdown(args.markdown, rows)
        if args.fixture:
            write_fixture(args.fixture, rows)
        if args.only == "contact":
            print(f"\n(decks and results in {work})")
            return
        print()

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
