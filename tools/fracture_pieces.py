#!/usr/bin/env python3
"""Per frame and per tracked piece: how a `femreg register` result on a fracture sequence errs.

    python3 tools/fracture_pieces.py OUT datasets/beam_break

OUT is a `femreg register` output folder (OUT/frames/<object>_NNNN.vtu, with the
original_vertex array), the dataset folder has ground_truth/frame_NNNN.csv and, after the
break, frame_NNNN_pieces.csv. Each tracked piece is matched to a ground-truth piece as
`femreg register` does (femreg/eval.h, ComputePieceErrors). Only the vertices with a true
position on their piece's match are counted here. Per piece:

  err_mm         mean vertex error
  rigid_mm       what is left of it after the best rigid fit of the tracked piece onto the
                 truth: the piece's own deformation error
  offset_mm      the truth's centroid minus the tracked centroid (x, y, z)
  strain_mm      the tracked piece's deviation from its rest shape (best rigid fit of its rest
                 shape onto it); truth_strain_mm the same for the truth
  length_mm      the tracked piece's extent along the truth piece's rest x axis, and the truth's

A piece that slides or stretches along its axis (data at its crack end pulling it) shows as a
large offset or length difference with a small rigid_mm or strain_mm.
"""
import argparse
import glob
import os
import re
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from femreg_tools import components, kabsch, read_vtu  # noqa: E402


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("out")
    parser.add_argument("dataset")
    args = parser.parse_args(argv)
    files = sorted(glob.glob(os.path.join(args.out, "frames", "*_[0-9][0-9][0-9][0-9].vtu")))
    if not files:
        sys.exit(f"{args.out}/frames: no <object>_NNNN.vtu files")
    print("frame piece n err_mm rigid_mm offset_mm strain_mm truth_strain_mm length_mm truth_length_mm")
    for path in files:
        frame = int(re.search(r"_(\d{4})\.vtu$", path).group(1))
        a = read_vtu(path)
        x = a["Points"]
        rest = x - a["displacement"]
        original = a["original_vertex"].astype(int)
        piece = components(len(x), a["connectivity"].reshape(-1, 4))
        gt = np.loadtxt(os.path.join(args.dataset, "ground_truth", f"frame_{frame:04d}.csv"),
                        delimiter=",", skiprows=1, ndmin=2)
        side = {}
        side_path = os.path.join(args.dataset, "ground_truth", f"frame_{frame:04d}_pieces.csv")
        if os.path.exists(side_path):
            for r in np.loadtxt(side_path, delimiter=",", skiprows=1, ndmin=2):
                side.setdefault(int(r[0]), {})[int(r[1])] = r[2:5]
        for p in range(piece.max() + 1):
            members = np.where(piece == p)[0]
            votes = {}
            for v in members:
                s = side.get(original[v])
                if s and len(s) == 1:
                    k = next(iter(s))
                    votes[k] = votes.get(k, 0) + 1
            match = max(votes, key=votes.get) if votes else None
            keep, truth = [], []
            for v in members:
                s = side.get(original[v])
                if s is None:
                    keep.append(v)
                    truth.append(gt[original[v], :3])
                elif match in s:
                    keep.append(v)
                    truth.append(s[match])
            if len(keep) < 4:
                continue
            keep, truth = np.array(keep), np.array(truth)
            xs, xr = x[keep], rest[keep]
            err = np.linalg.norm(xs - truth, axis=1).mean()
            r, t = kabsch(xs, truth)
            rigid = np.linalg.norm(xs @ r.T + t - truth, axis=1).mean()
            r1, t1 = kabsch(xr, xs)
            strain = np.linalg.norm(xr @ r1.T + t1 - xs, axis=1).mean()
            r2, t2 = kabsch(xr, truth)
            truth_strain = np.linalg.norm(xr @ r2.T + t2 - truth, axis=1).mean()
            axis = r2[:, 0]
            offset = truth.mean(0) - xs.mean(0)
            print(f"{frame} {p} {len(keep)} {err * 1e3:.2f} {rigid * 1e3:.2f} "
                  f"{offset[0] * 1e3:.2f},{offset[1] * 1e3:.2f},{offset[2] * 1e3:.2f} {strain * 1e3:.2f} "
                  f"{truth_strain * 1e3:.2f} {np.ptp(xs @ axis) * 1e3:.1f} {np.ptp(truth @ axis) * 1e3:.1f}")


if __name__ == "__main__":
    main()
