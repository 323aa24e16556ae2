#!/usr/bin/env python3
"""The physical failure metrics of a hand_press registration (issue 38), per frame and in total.

    python3 tools/hand_press_report.py OUT datasets/hand_press [--csv FILE] [--json FILE] [--table-z 0]

OUT is a `femreg register` output folder (OUT/frames/<object>_NNNN.vtu, OUT/stats.csv), the
dataset folder has ground_truth/frame_NNNN.csv (x,y,z,visible per tracked vertex). Per frame:

  seen_mm, hidden_mm   mean vertex error of the seen and the hidden vertices
  shape_mm             mean vertex error after the best rigid fit of the tracked vertices onto
                       the true ones: the error in the shape alone, not in the pose (a ball's
                       turn about its centre barely changes what a depth camera sees)
  inverted             tracked elements with signed volume <= 0
  min_z_mm             the tracked mesh's lowest point; truth_min_z_mm the truth's
  base_gap_mm          min_z - truth_min_z: > 0, the base lifted off where the truth rests
  penetration_mm       how far the tracked mesh reaches below the table (z = --table-z)
  top_gap_mm           the tracked top minus the truth's: > 0, it climbed (into the hand)
  rot_deg, truth_rot_deg  rotation from rest of the best rigid fit (Kabsch) to the tracked
                       and to the true vertex positions; rot_err_deg the angle between the two
  fit_rms_mm           rms_residual_mm of stats.csv (the data pairs' residual: the fit to the
                       cloud, the hand's points included)
  ball_points          the cloud's points of the ball: within --ball-band of the true surface
                       (truth/frame_NNNN.vtu; the rest is the hand's)
  ball_fit_mm          their median distance to the tracked mesh's surface; ball_beyond_5mm_pct
                       the share of them beyond 5 mm (issue 38: a 1 mm median, at most 3 %)
  capped               1 when the frame stopped at the outer-iteration cap
  lost                 1 when it found no correspondence (the mesh left the cloud)
  ms                   t_total_ms of stats.csv

Only numpy and the standard library (the VTU reader and the rigid fit are tools/femreg_tools.py's).
"""
import argparse
import csv
import glob
import os
import re
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from femreg_tools import kabsch, read_vtu  # noqa: E402

def read_truth(path):
    rows = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    return rows[:, :3], rows[:, 3] > 0.5


def rigid_fit_error(x, truth):
    """Per vertex, the distance to the truth of x moved by its best rigid fit onto the truth."""
    r, t = kabsch(x, truth)
    return np.linalg.norm(x @ r.T + t - truth, axis=1)


def angle_deg(r):
    return float(np.degrees(np.arccos(np.clip((np.trace(r) - 1.0) / 2.0, -1.0, 1.0))))


def signed_volumes(x, tets):
    a, b, c, d = (x[tets[:, k]] for k in range(4))
    return np.einsum("ij,ij->i", np.cross(b - a, c - a), d - a) / 6.0


def read_pcd_points(path):
    """The x, y, z of a PCD file (ascii or binary, any float fields besides)."""
    data = open(path, "rb").read()
    header, pos = {}, 0
    while True:
        end = data.index(b"\n", pos)
        line = data[pos:end].decode("ascii", "replace").strip()
        pos = end + 1
        if not line or line.startswith("#"):
            continue
        key, _, value = line.partition(" ")
        header[key.upper()] = value.split()
        if key.upper() == "DATA":
            break
    fields = header["FIELDS"]
    sizes = [int(v) for v in header["SIZE"]]
    types = header["TYPE"]
    counts = [int(v) for v in header.get("COUNT", ["1"] * len(fields))]
    n = int(header["POINTS"][0])
    kind = header["DATA"][0]
    if kind == "ascii":
        rows = np.loadtxt(data[pos:].decode().splitlines(), ndmin=2)
        col = {f: sum(counts[:i]) for i, f in enumerate(fields)}
        return rows[:n, [col["x"], col["y"], col["z"]]].astype(float)
    if kind != "binary":
        sys.exit(f"{path}: DATA {kind} is not read here (ascii or binary)")
    dtype = np.dtype([(f, {"F": "<f", "I": "<i", "U": "<u"}[t] + str(sz), (c,) if c > 1 else ())
                      for f, sz, t, c in zip(fields, sizes, types, counts)])
    rec = np.frombuffer(data, dtype, n, pos)
    return np.stack([rec["x"], rec["y"], rec["z"]], axis=1).astype(float)


def boundary_triangles(tets):
    """The faces of a tetrahedral mesh that belong to one tetrahedron only."""
    faces = np.concatenate([tets[:, [1, 2, 3]], tets[:, [0, 3, 2]], tets[:, [0, 1, 3]], tets[:, [0, 2, 1]]])
    key = np.sort(faces, axis=1)
    _, index, count = np.unique(key, axis=0, return_index=True, return_counts=True)
    return faces[index[count == 1]]


def closest_on_triangles(p, a, b, c):
    """Per row, the point of triangle (a, b, c) closest to p (Voronoi regions of the triangle)."""
    ab, ac, ap = b - a, c - a, p - a
    d1, d2 = np.einsum("ij,ij->i", ab, ap), np.einsum("ij,ij->i", ac, ap)
    bp = p - b
    d3, d4 = np.einsum("ij,ij->i", ab, bp), np.einsum("ij,ij->i", ac, bp)
    cp = p - c
    d5, d6 = np.einsum("ij,ij->i", ab, cp), np.einsum("ij,ij->i", ac, cp)
    va, vb, vc = d3 * d6 - d5 * d4, d5 * d2 - d1 * d6, d1 * d4 - d3 * d2
    denom = va + vb + vc
    denom = np.where(np.abs(denom) > 0, denom, 1.0)
    v, w = vb / denom, vc / denom
    out = a + ab * v[:, None] + ac * w[:, None]  # inside the face
    with np.errstate(divide="ignore", invalid="ignore"):
        # edges, then vertices (later assignments win)
        t = np.clip(d1 / (d1 - d3), 0, 1)
        m = (vc <= 0) & (d1 >= 0) & (d3 <= 0)
        out[m] = (a + ab * t[:, None])[m]
        t = np.clip(d2 / (d2 - d6), 0, 1)
        m = (vb <= 0) & (d2 >= 0) & (d6 <= 0)
        out[m] = (a + ac * t[:, None])[m]
        t = np.clip((d4 - d3) / ((d4 - d3) + (d5 - d6)), 0, 1)
        m = (va <= 0) & ((d4 - d3) >= 0) & ((d5 - d6) >= 0)
        out[m] = (b + (c - b) * t[:, None])[m]
    m = (d1 <= 0) & (d2 <= 0)
    out[m] = a[m]
    m = (d3 >= 0) & (d4 <= d3)
    out[m] = b[m]
    m = (d6 >= 0) & (d5 <= d6)
    out[m] = c[m]
    return out


def surface_distance(points, x, triangles, candidates=12):
    """Each point's distance to the triangle surface (x, triangles): exact over the triangles
    of the nearest centroids (enough where triangles are of similar size)."""
    a, b, c = x[triangles[:, 0]], x[triangles[:, 1]], x[triangles[:, 2]]
    centroids = (a + b + c) / 3.0
    k = min(candidates, len(triangles))
    best = np.full(len(points), np.inf)
    for start in range(0, len(points), 2048):
        p = points[start:start + 2048]
        d2 = ((p[:, None, :] - centroids[None, :, :]) ** 2).sum(axis=2)
        near = np.argpartition(d2, k - 1, axis=1)[:, :k]
        for j in range(k):
            t = near[:, j]
            q = closest_on_triangles(p, a[t], b[t], c[t])
            best[start:start + 2048] = np.minimum(best[start:start + 2048], np.linalg.norm(p - q, axis=1))
    return best


def stats_rows(out):
    path = os.path.join(out, "stats.csv")
    if not os.path.exists(path):
        return {}
    with open(path, newline="") as f:
        return {int(row["frame"]): row for row in csv.DictReader(f)}


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("out", help="femreg register output folder")
    parser.add_argument("dataset", help="the dataset folder (ground_truth/)")
    parser.add_argument("--object", default=None, help="object name (default: the only one)")
    parser.add_argument("--table-z", type=float, default=0.0, help="height of the table plane (m)")
    parser.add_argument("--csv", default=None, help="also write the per-frame rows here")
    parser.add_argument("--json", default=None, help="also write the totals here (a JSON object)")
    parser.add_argument("--ball-band", type=float, default=3.0,
                        help="a cloud point within this many mm of the true surface is the ball's (default 3)")
    args = parser.parse_args(argv)

    files = sorted(glob.glob(os.path.join(args.out, "frames", "*_[0-9][0-9][0-9][0-9].vtu")))
    objects = sorted({re.sub(r"_\d{4}\.vtu$", "", os.path.basename(f)) for f in files})
    if not objects:
        sys.exit(f"{args.out}/frames: no <object>_NNNN.vtu files")
    name = args.object or objects[0]
    if args.object is None and len(objects) > 1:
        sys.exit(f"several objects ({', '.join(objects)}): choose one with --object")
    stats = stats_rows(args.out)
    rows = []
    ball_fits = []
    for path in [f for f in files if os.path.basename(f).startswith(name + "_")]:
        frame = int(re.search(r"_(\d{4})\.vtu$", path).group(1))
        truth_path = os.path.join(args.dataset, "ground_truth", f"frame_{frame:04d}.csv")
        if not os.path.exists(truth_path):
            continue
        mesh = read_vtu(path)
        x = mesh["Points"].astype(float)
        tets = mesh["connectivity"].astype(np.int64).reshape(-1, 4)
        rest = x - mesh["displacement"] if "displacement" in mesh else None
        truth, seen = read_truth(truth_path)
        err = np.linalg.norm(x - truth, axis=1) * 1e3
        row = {
            "frame": frame,
            "seen_mm": float(err[seen].mean()) if seen.any() else float("nan"),
            "hidden_mm": float(err[~seen].mean()) if (~seen).any() else float("nan"),
            "shape_mm": float(rigid_fit_error(x, truth).mean() * 1e3),
            "inverted": int((signed_volumes(x, tets) <= 0).sum()),
            "min_z_mm": float(x[:, 2].min() * 1e3),
            "truth_min_z_mm": float(truth[:, 2].min() * 1e3),
            "penetration_mm": max(0.0, float((args.table_z - x[:, 2].min()) * 1e3)),
            "top_gap_mm": float((x[:, 2].max() - truth[:, 2].max()) * 1e3),
        }
        row["base_gap_mm"] = row["min_z_mm"] - row["truth_min_z_mm"]
        if rest is not None:
            r_track, r_truth = kabsch(rest, x)[0], kabsch(rest, truth)[0]
            row["rot_deg"] = angle_deg(r_track)
            row["truth_rot_deg"] = angle_deg(r_truth)
            row["rot_err_deg"] = angle_deg(r_track @ r_truth.T)
        s = stats.get(frame)
        row["lost"] = int(s is not None and s.get("termination") == "no_correspondences")
        have_fit = s is not None and s.get("rms_residual_mm") and not row["lost"]
        row["fit_rms_mm"] = float(s["rms_residual_mm"]) if have_fit else float("nan")
        row["capped"] = int(s is not None and s.get("termination") == "max_iterations")
        row["ms"] = float(s["t_total_ms"]) if s is not None and s.get("t_total_ms") else float("nan")
        cloud_path = os.path.join(args.dataset, "clouds", f"frame_{frame:04d}.pcd")
        surface_path = os.path.join(args.dataset, "truth", f"frame_{frame:04d}.vtu")
        if os.path.exists(cloud_path) and os.path.exists(surface_path):
            cloud = read_pcd_points(cloud_path)
            surface = read_vtu(surface_path)
            true_tris = surface["connectivity"].astype(np.int64).reshape(-1, 3)
            near = surface_distance(cloud, surface["Points"].astype(float), true_tris) * 1e3
            ball = cloud[near <= args.ball_band]
            fit = surface_distance(ball, x, boundary_triangles(tets)) * 1e3 if len(ball) else np.array([])
            row["ball_points"] = int(len(ball))
            row["ball_fit_mm"] = float(np.median(fit)) if len(fit) else float("nan")
            row["ball_beyond_5mm_pct"] = float(100.0 * (fit > 5.0).mean()) if len(fit) else float("nan")
            ball_fits.append(fit)
        rows.append(row)
    if not rows:
        sys.exit("no frame has both a registered mesh and a ground truth")

    columns = ["frame", "seen_mm", "hidden_mm", "shape_mm", "inverted", "min_z_mm", "truth_min_z_mm",
               "base_gap_mm", "penetration_mm", "top_gap_mm", "rot_deg", "truth_rot_deg",
               "rot_err_deg", "fit_rms_mm", "ball_points", "ball_fit_mm", "ball_beyond_5mm_pct",
               "capped", "lost", "ms"]
    columns = [c for c in columns if c in rows[0]]

    def cell(v):
        return f"{v:.2f}" if isinstance(v, float) else str(v)

    widths = [max(len(c), 7) for c in columns]
    print("  ".join(c.rjust(w) for c, w in zip(columns, widths)))
    for row in rows:
        print("  ".join(cell(row[c]).rjust(w) for c, w in zip(columns, widths)))
    n = len(rows)

    def col(c):
        return np.array([r[c] for r in rows], dtype=float)

    print()
    print(f"frames: {n}")
    print(f"mean error: seen {np.nanmean(col('seen_mm')):.2f} mm, hidden {np.nanmean(col('hidden_mm')):.2f} mm; "
          f"after the best rigid fit (the shape alone) {np.nanmean(col('shape_mm')):.2f} mm")
    inv = col("inverted")
    print(f"inverted elements: in {int((inv > 0).sum())} frames, at most {int(inv.max())}")
    print(f"base above the truth's: at most {col('base_gap_mm').max():.2f} mm "
          f"({int((col('base_gap_mm') > 5).sum())} frames beyond 5 mm)")
    print(f"penetration below the table: at most {col('penetration_mm').max():.2f} mm "
          f"({int((col('penetration_mm') > 1).sum())} frames beyond 1 mm)")
    print(f"top above the truth's: at most {col('top_gap_mm').max():.2f} mm")
    if "rot_err_deg" in rows[0]:
        err = col("rot_err_deg")
        print(f"rotation against the truth: mean {err.mean():.1f} deg, at most {err.max():.1f} deg "
              f"({int((err > 10).sum())} frames beyond 10 deg, {int((err > 60).sum())} beyond 60 deg)")
    print(f"fit to the cloud: median rms residual {np.nanmedian(col('fit_rms_mm')):.2f} mm")
    if ball_fits:
        fits = np.concatenate(ball_fits)
        print(f"fit of the ball's points to the tracked surface: median {np.median(fits):.2f} mm, "
              f"{100.0 * (fits > 5.0).mean():.1f} % beyond 5 mm ({len(fits)} points in {len(ball_fits)} frames)")
    print(f"frames at the outer-iteration cap: {int(col('capped').sum())} of {n}, "
          f"without correspondences: {int(col('lost').sum())}")
    print(f"time: {np.nanmean(col('ms')):.1f} ms per frame (mean)")
    if args.json:
        import json
        totals = {
            "frames": n,
            "seen_mm": float(np.nanmean(col("seen_mm"))),
            "hidden_mm": float(np.nanmean(col("hidden_mm"))),
            "shape_mm": float(np.nanmean(col("shape_mm"))),
            "inverted_frames": int((inv > 0).sum()),
            "max_base_gap_mm": float(col("base_gap_mm").max()),
            "max_penetration_mm": float(col("penetration_mm").max()),
            "max_rot_err_deg": float(col("rot_err_deg").max()) if "rot_err_deg" in rows[0] else None,
            "ball_fit_median_mm": float(np.median(np.concatenate(ball_fits))) if ball_fits else None,
            "ball_beyond_5mm_pct": float(100.0 * (np.concatenate(ball_fits) > 5.0).mean()) if ball_fits else None,
            "capped_frames": int(col("capped").sum()),
            "lost_frames": int(col("lost").sum()),
            "median_ms": float(np.nanmedian(col("ms"))),
            "mean_ms": float(np.nanmean(col("ms"))),
        }
        with open(args.json, "w") as f:
            json.dump(totals, f, indent=1)
    if args.csv:
        with open(args.csv, "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(columns)
            for row in rows:
                w.writerow([cell(row[c]) for c in columns])


if __name__ == "__main__":
    main()
