#!/usr/bin/env python3
"""How well the per-frame confidence separates good frames from failed ones (issue 39).

    python3 tools/confidence_roc.py [--femreg build/femreg] [--out /tmp/confidence_roc]

Registers the bundled datasets as they are (the good frames, mostly) and with generated
failures, and reports the area under the ROC curve of stats.csv's `confidence` as a
classifier of good against failed frames. The failures, each from a third of the way in:

  leave     the object leaves the view: a plane sweeps across the cloud and drops what is
            beyond it, over the cloud's extent in ten frames, then comes back;
  outliers  70 % of the points replaced by uniform noise over the cloud's box (+3 cm);
  swap      the clouds of another dataset (another object, elsewhere);
  pose      (free objects) the mesh's rest pose turned by 0.8 rad about z. (Turned by
            1.6 rad, fast_motion's box is found upside down: its surface fits, its vertices
            are 180 deg off. No confidence from the cloud can see that; such frames are
            ambiguous, not failed, and left out.)

A frame failed if its mean vertex error exceeds max(5 mm, 3x the clean run's median); held
frames (no solve: an empty or too small cloud, confidence 0) are counted apart, not in the
ROC. Needs the femreg Python module (build/python) for the clouds, numpy, and the CLI.
"""
import argparse
import csv
import os
import shutil
import subprocess
import sys

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DATASETS = ["demo", "occlusion", "fast_motion", "sag_track", "beam_bend", "block_press",
            "slab_stretch", "organ_patch", "tool_table", "contact_pair", "hand_press"]
SWAPS = {"demo": "sag_track", "occlusion": "fast_motion", "fast_motion": "beam_bend",
         "sag_track": "demo", "beam_bend": "block_press"}


def frames_of(dataset):
    folder = os.path.join(ROOT, "datasets", dataset, "clouds")
    return [os.path.join(folder, f) for f in sorted(os.listdir(folder)) if f.endswith(".pcd")]


def register(femreg, dataset, clouds, out, extra=()):
    if os.path.exists(out):
        shutil.rmtree(out)
    d = os.path.join(ROOT, "datasets", dataset)
    cmd = [femreg, "register", "--scene", os.path.join(d, "scene.yaml"), "--frames", clouds,
           "--ground-truth", os.path.join(d, "ground_truth"), "--out", out, "--threads", "1",
           *extra]
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    with open(os.path.join(out, "stats.csv")) as f:
        return list(csv.DictReader(f))


def write_clouds(fm, dataset, folder, change):
    """Copies the dataset's clouds into folder, frame i through change(i, points, n)."""
    os.makedirs(folder, exist_ok=True)
    files = frames_of(dataset)
    for i, path in enumerate(files):
        points = np.asarray(fm.read_point_cloud(path)[0].points)
        points = change(i, points, len(files))
        fm.write_point_cloud(os.path.join(folder, os.path.basename(path)),
                             np.ascontiguousarray(points, dtype=np.float64))


def leave(i, points, n):
    start = n // 3
    if i < start or len(points) == 0:
        return points
    # The cut plane sweeps along the cloud's longest axis: 10 frames out, 10 back.
    t = i - start
    fraction = min(t, 20 - t) / 10.0 if t < 20 else 0.0
    axis = int(np.argmax(points.max(0) - points.min(0)))
    lo, hi = points[:, axis].min(), points[:, axis].max()
    cut = hi - fraction * (hi - lo) * 1.001
    return points[points[:, axis] <= cut]


def outliers(i, points, n):
    if i < n // 3 or len(points) == 0:
        return points
    rng = np.random.default_rng(100 + i)
    lo, hi = points.min(0) - 0.03, points.max(0) + 0.03
    out = points.copy()
    k = int(0.7 * len(points))
    idx = rng.choice(len(points), k, replace=False)
    out[idx] = lo + rng.random((k, 3)) * (hi - lo)
    return out


def labelled(rows, reference_median):
    """(confidence, failed) per solved frame, and the held frames' count."""
    limit = max(5.0, 3.0 * reference_median)
    out, held = [], 0
    for r in rows:
        if r["termination"] not in ("converged", "max_iterations", "time_budget", "stalled") or not r["err_mean_mm"]:
            held += 1
            continue
        out.append((float(r["confidence"]), float(r["err_mean_mm"]) > limit))
    return out, held


def auc(samples):
    """P(confidence of a good frame > that of a failed one), ties counting half."""
    good = [c for c, failed in samples if not failed]
    bad = [c for c, failed in samples if failed]
    if not good or not bad:
        return float("nan")
    wins = sum((g > b) + 0.5 * (g == b) for g in good for b in bad)
    return wins / (len(good) * len(bad))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--femreg", default=os.path.join(ROOT, "build", "femreg"))
    ap.add_argument("--python-path", default=os.path.join(ROOT, "build", "python"))
    ap.add_argument("--out", default="/tmp/confidence_roc")
    args = ap.parse_args()
    sys.path.insert(0, args.python_path)
    import femreg as fm  # noqa: E402 (the module in the build tree)

    os.makedirs(args.out, exist_ok=True)
    samples, table, held_total = [], [], 0
    for dataset in DATASETS:
        clean = register(args.femreg, dataset, os.path.join(ROOT, "datasets", dataset, "clouds"),
                         os.path.join(args.out, dataset, "clean"))
        median = float(np.median([float(r["err_mean_mm"]) for r in clean if r["err_mean_mm"]]))
        runs = [("clean", clean)]
        if dataset in SWAPS:
            for name, change in (("leave", leave), ("outliers", outliers)):
                folder = os.path.join(args.out, dataset, name + "_clouds")
                write_clouds(fm, dataset, folder, change)
                runs.append((name, register(args.femreg, dataset, folder, os.path.join(args.out, dataset, name))))
            other = frames_of(SWAPS[dataset])
            mine = frames_of(dataset)
            folder = os.path.join(args.out, dataset, "swap_clouds")
            os.makedirs(folder, exist_ok=True)
            for i, path in enumerate(mine):
                source = path if i < len(mine) // 3 else other[min(i, len(other) - 1)]
                shutil.copy(source, os.path.join(folder, os.path.basename(path)))
            runs.append(("swap", register(args.femreg, dataset, folder, os.path.join(args.out, dataset, "swap"))))
        if dataset == "fast_motion":
            for angle in (0.8,):
                extra = ["--set", f"objects[0].pose.rotation=[0,0,{angle}]"]
                runs.append((f"pose {angle}", register(args.femreg, dataset,
                                                       os.path.join(ROOT, "datasets", dataset, "clouds"),
                                                       os.path.join(args.out, dataset, f"pose_{angle}"), extra)))
        for name, rows in runs:
            s, held = labelled(rows, median)
            samples += s
            held_total += held
            good = [c for c, f in s if not f]
            bad = [c for c, f in s if f]
            table.append((dataset, name, len(good), len(bad), held,
                          np.median(good) if good else float("nan"),
                          np.median(bad) if bad else float("nan")))
    print(f"{'dataset':12s} {'run':9s} {'good':>5s} {'failed':>6s} {'held':>5s} {'conf good':>9s} {'conf failed':>11s}")
    for d, n, g, b, h, cg, cb in table:
        print(f"{d:12s} {n:9s} {g:5d} {b:6d} {h:5d} {cg:9.3f} {cb:11.3f}")
    good = sum(1 for _, f in samples if not f)
    print(f"ROC area of the confidence: {auc(samples):.3f} over {good} good and "
          f"{len(samples) - good} failed frames ({held_total} held frames left out)")
    for threshold in (0.2, 0.3, 0.5):
        tp = sum(1 for c, f in samples if f and c < threshold)
        fp = sum(1 for c, f in samples if not f and c < threshold)
        print(f"  confidence < {threshold}: {tp} of {len(samples) - good} failed frames, "
              f"{fp} of {good} good ones")


if __name__ == "__main__":
    main()
