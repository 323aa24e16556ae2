#!/usr/bin/env python3
"""Track a sequence from Python: a scene, one cloud (or depth image) per frame, the
deformed mesh out.

    python3 examples/track.py datasets/demo/scene.yaml datasets/demo/clouds \
        --ground-truth datasets/demo/ground_truth --out /tmp/track_py
    python3 examples/track.py datasets/demo/scene.yaml datasets/demo/depth   # 16-bit PNGs

Frames are listed as `femreg register --frames` lists them (femreg.list_frames): a folder's
.pcd / .ply / .xyz / .txt clouds and .png / .npy depth images in name order, or a TUM RGB-D
sequence in its list's order. Depth images are back-projected through the scene's camera
(PNG: millimetres, or TUM's 1/5000 m, unless --depth-scale; a float .npy: metres). With
--out, writes OUT/<object>_NNNN.vtu per frame (open in ParaView) and OUT/summary.csv.
"""
import argparse
import csv
import pathlib
import sys

import numpy as np

import femreg

def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scene", help="scene file (YAML)")
    parser.add_argument("frames", help="folder of clouds or depth images, or a TUM RGB-D sequence")
    parser.add_argument("--ground-truth", help="folder of frame_NNNN.csv (x,y,z,visible)")
    parser.add_argument("--depth-scale", type=float,
                        help="metres per depth unit of PNG frames (default 0.001; TUM: 1/5000)")
    parser.add_argument("--out", help="folder for VTU files and summary.csv")
    args = parser.parse_args()

    try:
        scene = femreg.load_scene(args.scene)
        tracker = femreg.Tracker(scene)
        files, info = femreg.list_frames(args.frames)  # a TUM sequence in its list's order
    except femreg.Error as error:  # the message names the file, line and key
        sys.exit(f"track.py: {error}")
    frames = [pathlib.Path(f) for f in files]
    depth_scale = args.depth_scale or info["depth_scale"] or 0.001
    truth = sorted(pathlib.Path(args.ground_truth).glob("frame_*.csv")) if args.ground_truth else []
    out = pathlib.Path(args.out) if args.out else None
    if out:
        out.mkdir(parents=True, exist_ok=True)
    mesh = tracker.mesh(0)
    rows = []
    for f, path in enumerate(frames):
        if path.suffix.lower() == ".png":
            depth = femreg.read_depth_png(str(path))         # (H, W) uint16
            x = tracker.track_depth(depth, depth_scale=depth_scale)
        elif path.suffix.lower() == ".npy":
            depth = femreg.read_depth_npy(str(path))         # float32 metres or uint16 units
            x = tracker.track_depth(depth, depth_scale=depth_scale)
        else:
            cloud, _ = femreg.read_point_cloud(str(path))
            x = tracker.track(cloud.points, cloud.normals)   # (V, 3) numpy array
        s = tracker.summary                                   # the frame summary as a dict
        row = {"frame": f, "file": path.name, "termination": s["termination"],
               "points": s["points_used"], "outer_iterations": s["outer_iterations"],
               "rms_residual_mm": 1e3 * s["rms_residual"], "time_ms": 1e3 * s["time_s"]["total"]}
        if f < len(truth):
            true = np.loadtxt(truth[f], delimiter=",", skiprows=1)[:, :3]
            row["mean_error_mm"] = 1e3 * np.linalg.norm(x - true, axis=1).mean()
        rows.append(row)
        print(" ".join(f"{k}={v:.3f}" if isinstance(v, float) else f"{k}={v}"
                       for k, v in row.items()))
        if out:
            femreg.write_vtu(str(out / f"{scene.object_names[0]}_{f:04d}.vtu"), mesh, x,
                             fields={"displacement": x - mesh.rest,
                                     "residual": tracker.vertex_residuals(0),
                                     "observed": tracker.vertex_observed(0).astype(float)})
    if out:
        with open(out / "summary.csv", "w", newline="") as handle:
            writer = csv.DictWriter(handle, fieldnames=list(rows[-1].keys()))
            writer.writeheader()
            writer.writerows(rows)
        print(f"wrote {len(rows)} frames to {out}")
    if truth:
        print(f"mean vertex error over {len(rows)} frames: "
              f"{np.mean([r['mean_error_mm'] for r in rows]):.3f} mm")


if __name__ == "__main__":
    main()
