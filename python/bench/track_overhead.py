#!/usr/bin/env python3
"""Per-frame overhead of the Python tracker over the C++ call, on the bundled demo.

For every frame, the wall time of `tracker.track(points, normals)` (numpy in, the (V, 3)
numpy result out) is set against the time the C++ Tracker::Track measured for itself
(summary["time_s"]["total"]); the difference is what the binding costs: the argument
checks, the copy of the cloud into the tracker's buffer, releasing and taking back the GIL
and the copy of the vertices out. Also times the binding alone (the copies in and out
around a frame that does nothing) on clouds of the demo's size and 100x larger.

    OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 PYTHONPATH=build/python \\
        python3 python/bench/track_overhead.py [--repeats 5]

Prints medians over frames and repeats (the first frame of each run is left out: it sets
up caches).
"""
import argparse
import pathlib
import statistics
import time

import numpy as np

import femreg

ROOT = pathlib.Path(__file__).resolve().parents[2]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--dataset", default=str(ROOT / "datasets" / "demo"))
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    dataset = pathlib.Path(args.dataset)
    scene = femreg.load_scene(str(dataset / "scene.yaml"))
    clouds = []
    for path in sorted((dataset / "clouds").glob("*.pcd")):
        cloud, _ = femreg.read_point_cloud(str(path))
        clouds.append((np.ascontiguousarray(cloud.points),
                       None if cloud.normals is None else np.ascontiguousarray(cloud.normals)))

    wall, inner, overhead = [], [], []
    for _ in range(args.repeats):
        tracker = femreg.Tracker(scene)
        for f, (points, normals) in enumerate(clouds):
            start = time.perf_counter()
            tracker.track(points, normals)
            elapsed = time.perf_counter() - start
            cxx = tracker.summary["time_s"]["total"]
            if f == 0:
                continue
            wall.append(elapsed)
            inner.append(cxx)
            overhead.append(elapsed - cxx)

    ms = 1e3
    print(f"{dataset.name}: {len(clouds)} frames x {args.repeats} runs, "
          f"{clouds[0][0].shape[0]} points per cloud")
    print(f"  track() wall time      median {statistics.median(wall) * ms:8.3f} ms")
    print(f"  C++ Track (its own)    median {statistics.median(inner) * ms:8.3f} ms")
    print(f"  overhead (difference)  median {statistics.median(overhead) * ms:8.3f} ms "
          f"({statistics.median(o / w for o, w in zip(overhead, wall)) * 100:.2f}% of the call), "
          f"p90 {np.percentile(overhead, 90) * ms:.3f} ms")

    # The binding alone: a cloud of NaN points is copied in like any other, then dropped by
    # the C++ side at once (an invalid-input frame), and the vertices are copied out;
    # time.total is what C++ spent on it.
    for scale in (1, 100):
        points = np.full((clouds[1][0].shape[0] * scale, 3), np.nan)
        tracker = femreg.Tracker(scene)
        mesh = tracker.mesh(0)
        samples = []
        for _ in range(200):
            start = time.perf_counter()
            tracker.track(points)
            samples.append(time.perf_counter() - start - tracker.summary["time_s"]["total"])
        print(f"  binding only, {points.shape[0]:7d} points, {mesh.num_vertices} vertices: "
              f"median {statistics.median(samples) * 1e6:8.1f} us per call")


if __name__ == "__main__":
    main()
