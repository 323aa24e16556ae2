#!/usr/bin/env python3
"""Lost and found (issue 39): the object leaves the view for ten frames and comes back.

    python3 tools/lost_and_found.py [--femreg build/femreg] [--out /tmp/lost_and_found]
                                    [--set KEY=VALUE ...]   (passed to femreg register)

For each sequence, `femreg synth DATASET/synth.yaml --artefact leave_view=10` makes the
object leave the view from a third of the way in. The script registers that sequence with
its tracking scene and prints:

  flagged   the frames without the object that were flagged lost (stats.csv `lost`), and
            the other frames that were flagged;
  before    the mean vertex error over the five frames before the object left;
  back      the first frame after its return whose error is within 2x `before`, counted
            from the return (the target: at most 5);
  after     the mean error over the frames from there to the end.

Needs the femreg CLI only (and the datasets' synth.yaml).
"""
import argparse
import csv
import os
import shutil
import subprocess

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SEQUENCES = ["beam_bend", "block_press", "demo", "fast_motion", "occlusion"]
LEAVE = 10


def run(femreg, dataset, out, sets):
    if os.path.exists(out):
        shutil.rmtree(out)
    data = os.path.join(out, "data")
    subprocess.run([femreg, "synth", os.path.join(ROOT, "datasets", dataset, "synth.yaml"),
                    "--out", data, "--no-progress", "--artefact", f"leave_view={LEAVE}"],
                   check=True, stdout=subprocess.DEVNULL)
    subprocess.run([femreg, "register", "--scene", os.path.join(data, "scene.yaml"), "--frames",
                    os.path.join(data, "clouds"), "--ground-truth", os.path.join(data, "ground_truth"),
                    "--out", os.path.join(out, "run"), "--threads", "1", "--no-progress",
                    "--report", "none", *[a for kv in sets for a in ("--set", kv)]], check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    with open(os.path.join(out, "run", "stats.csv")) as f:
        return list(csv.DictReader(f))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--femreg", default=os.path.join(ROOT, "build", "femreg"))
    ap.add_argument("--out", default="/tmp/lost_and_found")
    ap.add_argument("--set", action="append", default=[], help="a scene key for register")
    args = ap.parse_args()
    print(f"{'sequence':12s} {'flagged':>9s} {'others':>6s} {'before mm':>9s} {'back in':>7s} {'after mm':>8s}")
    for dataset in SEQUENCES:
        rows = run(args.femreg, dataset, os.path.join(args.out, dataset), args.set)
        n = len(rows)
        start = n // 3  # the synth's default leave_start
        gone = range(start, min(n, start + LEAVE))
        err = [float(r["err_mean_mm"]) if r["err_mean_mm"] else float("nan") for r in rows]
        lost = [r["lost"] == "1" for r in rows]
        flagged = sum(lost[i] for i in gone)
        others = sum(lost[i] for i in range(n) if i not in gone)
        before = sum(err[max(0, start - 5):start]) / len(err[max(0, start - 5):start])
        back = next((k for k, i in enumerate(range(start + LEAVE, n)) if err[i] <= 2 * before), None)
        after = err[start + LEAVE + back:] if back is not None else []
        print(f"{dataset:12s} {flagged:4d} of {len(gone):2d} {others:6d} {before:9.2f} "
              f"{('%d' % back) if back is not None else 'never':>7s} "
              f"{(sum(after) / len(after)) if after else float('nan'):8.2f}")


if __name__ == "__main__":
    main()
