#!/usr/bin/env python3
"""The physical failure metrics of a hand_press registration (issue 38), per frame and in total.

    python3 tools/hand_press_report.py OUT datasets/hand_press [--csv FILE] [--table-z 0]

OUT is a `femreg register` output folder (OUT/frames/<object>_NNNN.vtu, OUT/stats.csv), the
dataset folder has ground_truth/frame_NNNN.csv (x,y,z,visible per tracked vertex). Per frame:

  seen_mm, hidden_mm   mean vertex error of the seen and the hidden vertices
  inverted             tracked elements with signed volume <= 0
  min_z_mm             the tracked mesh's lowest point; truth_min_z_mm the truth's
  base_gap_mm          min_z - truth_min_z: > 0, the base lifted off where the truth rests
  penetration_mm       how far the tracked mesh reaches below the table (z = --table-z)
  top_gap_mm           the tracked top minus the truth's: > 0, it climbed (into the hand)
  rot_deg, truth_rot_deg  rotation from rest of the best rigid fit (Kabsch) to the tracked
                       and to the true vertex positions; rot_err_deg the angle between the two
  fit_rms_mm           rms_residual_mm of stats.csv (the data pairs' residual: the fit to the
                       cloud, the hand's points included)
  capped               1 when the frame stopped at the outer-iteration cap
  lost                 1 when it found no correspondence (the mesh left the cloud)
  ms                   t_total_ms of stats.csv

Only numpy and the standard library (the VTU reader below handles what femreg writes:
appended raw data, zlib-compressed or not, UInt32 or UInt64 headers).
"""
import argparse
import csv
import glob
import os
import re
import sys
import zlib

import numpy as np

_TYPES = {"Float32": "<f4", "Float64": "<f8", "Int32": "<i4", "Int64": "<i8", "UInt8": "u1",
          "UInt32": "<u4", "UInt64": "<u8", "Int8": "i1", "Int16": "<i2", "UInt16": "<u2"}


def read_vtu(path):
    """The arrays of a VTU with appended raw data: {name: numpy array}, Points as 'Points'."""
    data = open(path, "rb").read()
    start = data.index(b"<AppendedData")
    head = data[:start].decode("utf-8", "replace")
    raw = data[data.index(b"_", start) + 1:]
    header_type = re.search(r'header_type="(\w+)"', head)
    htype = np.dtype(_TYPES[header_type.group(1)] if header_type else "<u4")
    compressed = "compressor=" in head.split(">", 1)[0]
    arrays = {}
    for tag in re.finditer(r"<DataArray([^>]*)>", head):
        attrs = dict(re.findall(r'(\w+)="([^"]*)"', tag.group(1)))
        if attrs.get("format") != "appended":
            continue
        offset = int(attrs["offset"])
        dtype = np.dtype(_TYPES[attrs["type"]])
        hs = htype.itemsize
        if compressed:
            nblocks = int(np.frombuffer(raw, htype, 1, offset)[0])
            sizes = np.frombuffer(raw, htype, 3 + nblocks, offset)
            pos = offset + hs * (3 + nblocks)
            chunks = []
            for size in sizes[3:]:
                chunks.append(zlib.decompress(raw[pos:pos + int(size)]))
                pos += int(size)
            payload = b"".join(chunks)
        else:
            nbytes = int(np.frombuffer(raw, htype, 1, offset)[0])
            payload = raw[offset + hs:offset + hs + nbytes]
        values = np.frombuffer(payload, dtype)
        components = int(attrs.get("NumberOfComponents", "1"))
        arrays[attrs.get("Name", "")] = values.reshape(-1, components) if components > 1 else values
    return arrays


def read_truth(path):
    rows = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    return rows[:, :3], rows[:, 3] > 0.5


def kabsch(rest, x):
    """The rotation of the best rigid fit of rest onto x (equal weights)."""
    a = rest - rest.mean(axis=0)
    b = x - x.mean(axis=0)
    u, _, vt = np.linalg.svd(a.T @ b)
    d = np.sign(np.linalg.det(vt.T @ u.T))
    return vt.T @ np.diag([1.0, 1.0, d]) @ u.T


def angle_deg(r):
    return float(np.degrees(np.arccos(np.clip((np.trace(r) - 1.0) / 2.0, -1.0, 1.0))))


def signed_volumes(x, tets):
    a, b, c, d = (x[tets[:, k]] for k in range(4))
    return np.einsum("ij,ij->i", np.cross(b - a, c - a), d - a) / 6.0


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
            "inverted": int((signed_volumes(x, tets) <= 0).sum()),
            "min_z_mm": float(x[:, 2].min() * 1e3),
            "truth_min_z_mm": float(truth[:, 2].min() * 1e3),
            "penetration_mm": max(0.0, float((args.table_z - x[:, 2].min()) * 1e3)),
            "top_gap_mm": float((x[:, 2].max() - truth[:, 2].max()) * 1e3),
        }
        row["base_gap_mm"] = row["min_z_mm"] - row["truth_min_z_mm"]
        if rest is not None:
            r_track, r_truth = kabsch(rest, x), kabsch(rest, truth)
            row["rot_deg"] = angle_deg(r_track)
            row["truth_rot_deg"] = angle_deg(r_truth)
            row["rot_err_deg"] = angle_deg(r_track @ r_truth.T)
        s = stats.get(frame)
        row["lost"] = int(s is not None and s.get("termination") == "no_correspondences")
        have_fit = s is not None and s.get("rms_residual_mm") and not row["lost"]
        row["fit_rms_mm"] = float(s["rms_residual_mm"]) if have_fit else float("nan")
        row["capped"] = int(s is not None and s.get("termination") == "max_iterations")
        row["ms"] = float(s["t_total_ms"]) if s is not None and s.get("t_total_ms") else float("nan")
        rows.append(row)
    if not rows:
        sys.exit("no frame has both a registered mesh and a ground truth")

    columns = ["frame", "seen_mm", "hidden_mm", "inverted", "min_z_mm", "truth_min_z_mm",
               "base_gap_mm", "penetration_mm", "top_gap_mm", "rot_deg", "truth_rot_deg",
               "rot_err_deg", "fit_rms_mm", "capped", "lost", "ms"]
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
    print(f"mean error: seen {np.nanmean(col('seen_mm')):.2f} mm, hidden {np.nanmean(col('hidden_mm')):.2f} mm")
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
    print(f"frames at the outer-iteration cap: {int(col('capped').sum())} of {n}, "
          f"without correspondences: {int(col('lost').sum())}")
    print(f"time: {np.nanmean(col('ms')):.1f} ms per frame (mean)")
    if args.csv:
        with open(args.csv, "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(columns)
            for row in rows:
                w.writerow([cell(row[c]) for c in columns])


if __name__ == "__main__":
    main()
