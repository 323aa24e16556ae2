#!/usr/bin/env python3
"""How far a dataset's error moves under nudges that should not matter, for one or two builds.

    python3 tools/nudged_runs.py DATASET [--femreg build/femreg] [--vs OTHER_FEMREG]
                                 [--nudges 7] [--out /tmp/nudged] [--threads 1]
                                 [--set KEY.PATH=VALUE ...]

Some sequences are sensitive: on hand_press a frame that stops one outer iteration earlier
lifts the ball at another turn, and the mean error of the whole sequence changes by a sixth.
One run of a build against another then says little about the change between them. This
registers DATASET once per nudge, each with `registration.solver.bulk_step_tolerance` moved
by a step of 2 % (0.94 to 1.06 times the scene's value for the default seven nudges), and
prints, per run and over the runs: the mean vertex error (mm), the outer iterations over the
sequence, the frames not converged, the median time per frame and the run's CPU seconds (user
and system: on a busy shared host the wall time per frame swings by tens of percent from one
run to the next, the CPU time far less). With --vs, the same nudges with the other build, and
the paired differences. --set passes scene overrides to every run
(e.g. --set registration.forces.estimate=true). Uses only the CLI and the standard library.
"""
import argparse
import csv
import json
import os
import resource
import statistics
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
KEY = "registration.solver.bulk_step_tolerance"
DEFAULT_BULK_STEP = 0.05  # RegistrationOptions::solver.bulk_step_tolerance's default


def scene_value(scene):
    """The scene's bulk_step_tolerance if it sets one (a plain YAML scan), else the default."""
    with open(scene) as f:
        for line in f:
            stripped = line.split("#", 1)[0]
            if "bulk_step_tolerance:" in stripped:
                try:
                    return float(stripped.split("bulk_step_tolerance:", 1)[1].strip().rstrip("}, "))
                except ValueError:
                    break
    return DEFAULT_BULK_STEP


def run(femreg, dataset, value, out, threads, overrides=()):
    folder = os.path.join(ROOT, "datasets", dataset)
    cmd = [femreg, "register", "--scene", os.path.join(folder, "scene.yaml"),
           "--frames", os.path.join(folder, "clouds"), "--out", out, "--force", "--no-progress",
           "--threads", str(threads), "--set", f"{KEY}={value:.6g}"]
    for override in overrides:
        cmd += ["--set", override]
    truth = os.path.join(folder, "ground_truth")
    if os.path.isdir(truth):
        cmd += ["--ground-truth", truth]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    done = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    if done.returncode != 0:
        sys.exit(f"nudged_runs: {' '.join(cmd)} failed:\n{done.stdout[-2000:]}")
    with open(os.path.join(out, "summary.json")) as f:
        summary = json.load(f)
    with open(os.path.join(out, "stats.csv")) as f:
        rows = list(csv.DictReader(f))
    error = (summary.get("vertex_error_mm") or {}).get("mean", float("nan"))
    return {
        "error": error,
        "outer": sum(int(r["outer_iterations"]) for r in rows),
        "capped": sum(r["termination"] != "converged" for r in rows),
        "ms": summary.get("ms_per_frame_median", float("nan")),
        "cpu": cpu,
    }


def describe(name, results):
    errors = [r["error"] for r in results]
    outer = [r["outer"] for r in results]
    print(f"{name}: mean error {statistics.mean(errors):.3f} mm (min {min(errors):.3f}, "
          f"max {max(errors):.3f}), outer iterations {statistics.mean(outer):.1f}, "
          f"frames not converged {statistics.mean(r['capped'] for r in results):.1f}, "
          f"CPU {statistics.mean(r['cpu'] for r in results):.2f} s per run")


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("dataset", help="a folder name under datasets/")
    parser.add_argument("--femreg", default=os.path.join(ROOT, "build", "femreg"))
    parser.add_argument("--vs", help="another femreg binary to compare with, nudge by nudge")
    parser.add_argument("--nudges", type=int, default=7, help="runs per build (odd: one is unnudged)")
    parser.add_argument("--out", default="/tmp/nudged")
    parser.add_argument("--threads", type=int, default=1)
    parser.add_argument("--set", action="append", default=[], metavar="KEY.PATH=VALUE",
                        help="a scene override for every run (repeatable)")
    args = parser.parse_args()
    if args.nudges < 1:
        sys.exit("nudged_runs: --nudges must be at least 1")
    base = scene_value(os.path.join(ROOT, "datasets", args.dataset, "scene.yaml"))
    half = args.nudges // 2
    factors = [1.0 + 0.02 * (k - half) for k in range(args.nudges)]
    builds = [("A", args.femreg)] + ([("B", args.vs)] if args.vs else [])
    results = {name: [] for name, _ in builds}
    print(f"{args.dataset}: {KEY} = {base:g} x " + ", ".join(f"{f:.2f}" for f in factors))
    print("nudge    " + "".join(f"{name + ' error mm':>14s}{'outer':>7s}{'capped':>8s}{'ms':>8s}{'cpu s':>8s}"
                                  for name, _ in builds))
    for k, factor in enumerate(factors):
        line = f"{factor:5.2f}    "
        for name, femreg in builds:  # alternated, so that a busy spell hits both
            r = run(femreg, args.dataset, base * factor, os.path.join(args.out, f"{name}_{k}"), args.threads,
                    args.set)
            results[name].append(r)
            line += f"{r['error']:14.3f}{r['outer']:7d}{r['capped']:8d}{r['ms']:8.1f}{r['cpu']:8.2f}"
        print(line, flush=True)
    for name, femreg in builds:
        describe(f"{name} ({femreg})", results[name])
    if args.vs:
        diffs = [b["error"] - a["error"] for a, b in zip(results["A"], results["B"])]
        print(f"B - A, paired: mean {statistics.mean(diffs):+.3f} mm, "
              f"min {min(diffs):+.3f}, max {max(diffs):+.3f}")
        ratios = [b["cpu"] / a["cpu"] for a, b in zip(results["A"], results["B"]) if a["cpu"] > 0]
        if ratios:
            print(f"B / A, CPU seconds per run: median {statistics.median(ratios):.2f} "
                  f"(min {min(ratios):.2f}, max {max(ratios):.2f})")


if __name__ == "__main__":
    main()
