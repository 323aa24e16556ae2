#!/usr/bin/env python3
"""Registers a slab built from one real DeepDeform frame to a later frame, and compares the
motion of the first frame's surface points with DeepDeform's ground-truth scene flow.

DeepDeform (https://github.com/AljazBozic/DeepDeform) is real RGB-D of deforming objects;
its samples are in DeformableFriends/NeuralTracking's example_data. Their licence is not
femreg's: they are never copied into the repository. Point --data at a sequence folder of
a copy:

  /usr/bin/python3 tools/deepdeform.py --femreg build/femreg \\
      --data $FEMREG_DEEPDEFORM_DIR/train/seq258 --out /tmp/deepdeform-run

A DeepDeform sequence folder holds depth/NNNNNN.png (16-bit, millimetres), intrinsics.txt
(the 4x4 camera matrix as numpy.savetxt writes it), mask/NNNNNN_<object>.png (the object in
the source frame), scene_flow/<object>_<src>_<tgt>.sflow and optical_flow/...oflow (per
source pixel: uint32 width, height, channels, then float32 [channels][height][width];
metres and pixels; non-finite where there is no truth).

What it does:
  1. the tracked body: the source frame's masked pixels on a grid (every --stride pixels),
     back-projected, and a copy of each pushed --thickness further along its camera ray: a
     slab behind the visible surface, each grid cell with its four corners on the object
     (and depths within --max-step of each other) split into six tetrahedra;
  2. the frames: source and target depth images as they are, through the sequence's
     intrinsics.txt; masks: the source frame's own, and for the target (--target-mask)
       flow: the source mask carried along the optical flow and closed (a stand-in for a
             segmentation of the target frame, which the sample does not have);
       box:  every pixel, cropped to the depth range of the source's object +- --margin;
  3. `femreg register` on the two frames, one thread, timed;
  4. each source pixel with a finite ground-truth flow gets the displacement of the slab's
     front face at it (bilinear over its grid cell; the nearest front vertex outside the
     slab's cells); end-point error = |predicted - true displacement|, against doing nothing
     (|true displacement|).

Writes OUT/report.json and prints a summary. Needs numpy, Pillow and VTK's Python module
(Debian: python3-numpy python3-pil python3-vtk9), and scipy for the nearest vertex.
"""

import argparse
import glob
import json
import os
import re
import struct
import subprocess
import sys
import time

import numpy as np
from PIL import Image
from scipy import ndimage
from scipy.spatial import cKDTree
import vtk
from vtk.util import numpy_support

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from femreg_tools import kabsch, read_vtu  # noqa: E402


def read_png(path):
    return np.array(Image.open(path)).astype(np.int64)


def read_flow(path):
    with open(path, "rb") as f:
        data = f.read()
    width, height, channels = struct.unpack("<III", data[:12])
    flow = np.frombuffer(data[12:], dtype="<f4")
    if flow.size != width * height * channels:
        sys.exit(f"{path}: {flow.size} values for {channels} x {height} x {width}")
    return flow.reshape(channels, height, width)


def read_intrinsics(path):
    k = np.loadtxt(path)
    return k[0, 0], k[1, 1], k[0, 2], k[1, 2]


def back_project(depth_m, fx, fy, cx, cy):
    h, w = depth_m.shape
    v, u = np.mgrid[0:h, 0:w]
    return np.stack([(u - cx) / fx * depth_m, (v - cy) / fy * depth_m, depth_m], axis=-1)


def build_slab(points, valid, stride, thickness, max_step):
    """Front vertices on the grid's valid pixels, back vertices `thickness` behind each along
    its ray; six tetrahedra per grid cell (the Kuhn split: every cell cut the same way, so
    neighbouring cells share their faces' diagonals)."""
    h, w = valid.shape
    rows = np.arange(0, h, stride)
    cols = np.arange(0, w, stride)
    grid_ok = valid[np.ix_(rows, cols)]
    index = -np.ones(grid_ok.shape, dtype=np.int64)
    index[grid_ok] = np.arange(grid_ok.sum())
    front = points[np.ix_(rows, cols)][grid_ok]
    rays = front / np.linalg.norm(front, axis=1, keepdims=True)
    back = front + thickness * rays
    vertices = np.vstack([front, back])
    n_front = len(front)
    depth = points[np.ix_(rows, cols)][..., 2]
    tets = []
    cells = []
    # The six tetrahedra of a cube around its diagonal 000-111, by the order in which the
    # three axes are stepped.
    perms = [(0, 1, 2), (0, 2, 1), (1, 0, 2), (1, 2, 0), (2, 0, 1), (2, 1, 0)]
    for i in range(len(rows) - 1):
        for j in range(len(cols) - 1):
            corners = index[i:i + 2, j:j + 2]
            if (corners < 0).any():
                continue
            d = depth[i:i + 2, j:j + 2]
            if d.max() - d.min() > max_step:
                continue
            cells.append((i, j))

            def vertex(bits):
                di, dj, k = bits
                return index[i + di, j + dj] + (n_front if k else 0)

            for p in perms:
                bits = [0, 0, 0]
                chain = [vertex(tuple(bits))]
                for axis in p:
                    bits[axis] = 1
                    chain.append(vertex(tuple(bits)))
                tets.append(chain)
    tets = np.array(tets, dtype=np.int64).reshape(-1, 6, 4)
    # The largest piece of cells joined by their edges: a mask's stray pixels (the wall
    # seen past the object's border) make islands of their own.
    cell_grid = np.zeros((len(rows) - 1, len(cols) - 1), dtype=bool)
    for i, j in cells:
        cell_grid[i, j] = True
    labels, count = ndimage.label(cell_grid)
    if count > 1:
        sizes = ndimage.sum(cell_grid, labels, range(1, count + 1))
        keep = labels[tuple(np.array(cells).T)] == 1 + int(np.argmax(sizes))
        tets = tets[keep]
    tets = tets.reshape(-1, 4)
    # Positive volumes (a tracked mesh is expected so).
    a, b, c, d = (vertices[tets[:, k]] for k in range(4))
    vol = np.einsum("ij,ij->i", np.cross(b - a, c - a), d - a)
    flip = vol < 0
    tets[flip, 2], tets[flip, 3] = tets[flip, 3].copy(), tets[flip, 2].copy()
    # Only the vertices of a tetrahedron, front ones first (femreg drops the others).
    used = np.zeros(len(vertices), dtype=bool)
    used[tets.ravel()] = True
    renumber = -np.ones(len(vertices), dtype=np.int64)
    renumber[used] = np.arange(used.sum())
    n_front_used = int(used[:n_front].sum())
    front_index = np.where(index >= 0, renumber[np.clip(index, 0, None)], -1)
    return vertices[used], renumber[tets], front_index, rows, cols, n_front_used


def write_vtu(path, vertices, tets):
    grid = vtk.vtkUnstructuredGrid()
    pts = vtk.vtkPoints()
    pts.SetData(numpy_support.numpy_to_vtk(np.ascontiguousarray(vertices, dtype=np.float64), deep=True))
    grid.SetPoints(pts)
    cells = vtk.vtkCellArray()
    for t in tets:
        cells.InsertNextCell(4, [int(x) for x in t])
    grid.SetCells(vtk.VTK_TETRA, cells)
    writer = vtk.vtkXMLUnstructuredGridWriter()
    writer.SetFileName(path)
    writer.SetInputData(grid)
    writer.SetDataModeToAscii()
    if not writer.Write():
        sys.exit(f"cannot write {path}")


def carried_mask(mask, oflow, depth_target):
    """The source mask moved along the optical flow to the target frame, closed over the
    holes the rounding leaves, kept where the target has a depth."""
    h, w = mask.shape
    v, u = np.nonzero(mask & np.isfinite(oflow).all(axis=0))
    tu = np.rint(u + oflow[0, v, u]).astype(np.int64)
    tv = np.rint(v + oflow[1, v, u]).astype(np.int64)
    inside = (tu >= 0) & (tu < w) & (tv >= 0) & (tv < h)
    out = np.zeros((h, w), dtype=bool)
    out[tv[inside], tu[inside]] = True
    out = ndimage.binary_closing(out, structure=np.ones((5, 5)), iterations=1)
    return out & (depth_target > 0)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--femreg", required=True, help="the femreg executable (or a wrapper)")
    ap.add_argument("--data", default=os.path.join(os.environ.get("FEMREG_DEEPDEFORM_DIR", ""), "train", "seq258"),
                    help="a DeepDeform sequence folder (default $FEMREG_DEEPDEFORM_DIR/train/seq258)")
    ap.add_argument("--object", default=None, help="the mask's object name (default: the only one)")
    ap.add_argument("--source", default=None, help="source frame number (default: the scene flow file's)")
    ap.add_argument("--target", default=None, help="target frame number (default: the scene flow file's)")
    ap.add_argument("--out", required=True)
    ap.add_argument("--stride", type=int, default=8, help="grid step of the slab's vertices (pixels)")
    ap.add_argument("--thickness", type=float, default=0.005, help="slab thickness along the rays (m)")
    ap.add_argument("--max-step", type=float, default=0.03, help="largest depth step inside a cell (m)")
    ap.add_argument("--target-mask", choices=["flow", "box"], default="flow")
    ap.add_argument("--frames", choices=["both", "target"], default="both",
                    help="register source then target (both), or the target alone from the slab (target: "
                         "the first frame's pose check and global search)")
    ap.add_argument("--start", choices=["slab", "rigid-truth"], default="slab",
                    help="where the target frame starts: from the slab as built (slab), or from the slab moved "
                         "by the rigid motion that fits the ground truth best (rigid-truth: an oracle that "
                         "separates finding the object from registering its deformation; implies --frames target)")
    ap.add_argument("--margin", type=float, default=0.1, help="--target-mask box: depth margin (m)")
    ap.add_argument("--youngs-modulus", type=float, default=5000.0)
    ap.add_argument("--poisson-ratio", type=float, default=0.3)
    ap.add_argument("--set", action="append", default=[], help="passed to femreg register (KEY=VALUE)")
    args = ap.parse_args()

    seq = args.data
    flows = sorted(glob.glob(os.path.join(seq, "scene_flow", "*.sflow")))
    if not flows:
        sys.exit(f"{seq}: no scene_flow/*.sflow (point --data or FEMREG_DEEPDEFORM_DIR at a DeepDeform copy)")
    pairs = [re.match(r"(.+)_(\d+)_(\d+)\.sflow$", os.path.basename(f)) for f in flows]
    pairs = [m for m in pairs if m and (args.object is None or m.group(1) == args.object)
             and (args.source is None or int(m.group(2)) == int(args.source))
             and (args.target is None or int(m.group(3)) == int(args.target))]
    if len(pairs) != 1:
        sys.exit(f"{seq}: {len(pairs)} scene flow files match; choose with --object, --source, --target")
    obj, src, tgt = pairs[0].group(1), pairs[0].group(2), pairs[0].group(3)
    os.makedirs(args.out, exist_ok=True)

    intrinsics_path = os.path.abspath(os.path.join(seq, "intrinsics.txt"))
    fx, fy, cx, cy = read_intrinsics(intrinsics_path)
    depth0 = read_png(os.path.join(seq, "depth", src + ".png"))
    depth1 = read_png(os.path.join(seq, "depth", tgt + ".png"))
    mask0 = read_png(os.path.join(seq, "mask", f"{src}_{obj}.png")) > 0
    sflow = read_flow(os.path.join(seq, "scene_flow", f"{obj}_{src}_{tgt}.sflow"))
    oflow = read_flow(os.path.join(seq, "optical_flow", f"{obj}_{src}_{tgt}.oflow"))
    h, w = depth0.shape
    scale = 0.001  # DeepDeform's depth PNGs are millimetres

    points0 = back_project(depth0 * scale, fx, fy, cx, cy)
    valid0 = mask0 & (depth0 > 0)
    vertices, tets, index, rows, cols, n_front = build_slab(points0, valid0, args.stride, args.thickness,
                                                                  args.max_step)
    # The ground truth: source pixels of the object with a finite scene flow.
    truth_ok = valid0 & np.isfinite(sflow).all(axis=0)
    tv, tu = np.nonzero(truth_ok)
    true = sflow[:, tv, tu].T.astype(np.float64)
    start = vertices
    if args.start == "rigid-truth":
        args.frames = "target"
        r, t = kabsch(points0[tv, tu], points0[tv, tu] + true)
        start = vertices @ r.T + t
    mesh_path = os.path.join(args.out, "slab.vtu")
    write_vtu(mesh_path, start, tets)

    # Frames and masks, named alike (femreg reads mask_dir/<frame name>.png).
    frames = os.path.join(args.out, "frames")
    masks = os.path.join(args.out, "masks")
    for d in (frames, masks):
        os.makedirs(d, exist_ok=True)
        for f in glob.glob(os.path.join(d, "*.png")):
            os.remove(f)
    for name in (src, tgt) if args.frames == "both" else (tgt,):
        os.symlink(os.path.abspath(os.path.join(seq, "depth", name + ".png")), os.path.join(frames, name + ".png"))
    Image.fromarray((mask0 * 255).astype(np.uint8)).save(os.path.join(masks, src + ".png"))
    if args.target_mask == "flow":
        mask1 = carried_mask(mask0, oflow, depth1)
    else:
        z = depth0[valid0] * scale
        z1 = depth1 * scale
        mask1 = (z1 > z.min() - args.margin) & (z1 < z.max() + args.margin)
    Image.fromarray((mask1 * 255).astype(np.uint8)).save(os.path.join(masks, tgt + ".png"))

    scene = os.path.join(args.out, "scene.yaml")
    with open(scene, "w") as f:
        f.write(f"""# A slab behind DeepDeform {os.path.basename(os.path.normpath(seq))} frame {src}'s {obj}, written by tools/deepdeform.py
objects:
  - name: {obj}
    mesh: slab.vtu
    material: {{youngs_modulus: {args.youngs_modulus:g}, poisson_ratio: {args.poisson_ratio:g}, density: 200}}
registration:
  camera: {{position: [0, 0, 0], target: [0, 0, 1], up: [0, -1, 0], intrinsics: {json.dumps(intrinsics_path)}, width: {w}, height: {h}}}
  data: {{visibility: true}}
""")
    run = os.path.join(args.out, "run")
    cmd = [args.femreg, "register", "--scene", scene, "--frames", frames, "--mask-dir", masks,
           "--depth-scale", str(scale), "--threads", "1", "--no-progress", "--out", run, "--force"]
    for s in args.set:
        cmd += ["--set", s]
    t0 = time.time()
    proc = subprocess.run(cmd, capture_output=True, text=True)
    seconds = time.time() - t0
    with open(os.path.join(args.out, "register.log"), "w") as f:
        f.write(" ".join(cmd) + "\n" + proc.stdout + proc.stderr)
    if proc.returncode != 0:
        sys.exit(f"femreg register failed ({proc.returncode}); see {args.out}/register.log\n{proc.stderr[-2000:]}")
    outs = sorted(glob.glob(os.path.join(run, "frames", f"{obj}_*.vtu")))
    expected = 2 if args.frames == "both" else 1
    if len(outs) != expected:
        sys.exit(f"{run}: expected {expected} frames of {obj}, found {outs}")
    x0 = read_vtu(outs[0])["Points"].astype(np.float64) if expected == 2 else start
    x1 = read_vtu(outs[-1])["Points"].astype(np.float64)
    disp = x1[:n_front] - vertices[:n_front]  # from the slab as built, not from the fit to frame 0

    gi = tv // args.stride
    gj = tu // args.stride
    ok_cell = (gi + 1 < len(rows)) & (gj + 1 < len(cols))
    pred = np.empty_like(true)
    in_cell = np.zeros(len(tv), dtype=bool)
    ids = np.full((len(tv), 4), -1, dtype=np.int64)
    ids[ok_cell] = np.stack([index[gi[ok_cell], gj[ok_cell]], index[gi[ok_cell], gj[ok_cell] + 1],
                             index[gi[ok_cell] + 1, gj[ok_cell]], index[gi[ok_cell] + 1, gj[ok_cell] + 1]], axis=1)
    in_cell = (ids >= 0).all(axis=1)
    a = (tu - cols[np.clip(gj, 0, len(cols) - 1)]) / args.stride
    b = (tv - rows[np.clip(gi, 0, len(rows) - 1)]) / args.stride
    wts = np.stack([(1 - a) * (1 - b), a * (1 - b), (1 - a) * b, a * b], axis=1)
    c = in_cell
    pred[c] = np.einsum("ik,ikj->ij", wts[c], disp[ids[c]])
    grid_v, grid_u = np.nonzero(index >= 0)
    tree = cKDTree(np.stack([cols[grid_u], rows[grid_v]], axis=1))
    _, nearest = tree.query(np.stack([tu[~c], tv[~c]], axis=1))
    pred[~c] = disp[index[grid_v, grid_u][nearest]]

    # The slab's own floor: its front vertices moved by the true flow at their pixels, read
    # back the same way (over the pixels whose four corners have a true flow).
    grid_true = np.full((n_front, 3), np.nan)
    grid_true[index[grid_v, grid_u]] = sflow[:, rows[grid_v], cols[grid_u]].T
    floor_ok = c & np.isfinite(grid_true[np.clip(ids, 0, None)]).all(axis=(1, 2))
    floor_pred = np.einsum("ik,ikj->ij", wts[floor_ok], grid_true[ids[floor_ok]])
    floor = np.linalg.norm(floor_pred - true[floor_ok], axis=1) * 1000
    epe = np.linalg.norm(pred - true, axis=1) * 1000
    # Where the target frame started, read back the same way (the slab as built: doing
    # nothing; the rigid oracle: its residual).
    start_disp = start[:n_front] - vertices[:n_front]
    start_pred = np.empty_like(true)
    start_pred[c] = np.einsum("ik,ikj->ij", wts[c], start_disp[ids[c]])
    start_pred[~c] = start_disp[index[grid_v, grid_u][nearest]]
    at_start = np.linalg.norm(start_pred - true, axis=1) * 1000
    still = np.linalg.norm(true, axis=1) * 1000
    # Along the camera ray (what a depth image measures at a pixel) and across it (in the
    # image plane: what the surface's shape and outline must tell).
    ray = points0[tv, tu] / np.linalg.norm(points0[tv, tu], axis=1, keepdims=True)

    def split(v):
        along = np.einsum("ij,ij->i", v, ray)
        return np.abs(along) * 1000, np.linalg.norm(v - along[:, None] * ray, axis=1) * 1000
    epe_along, epe_across = split(pred - true)
    start_along, start_across = split(start_pred - true)
    still_along, still_across = split(true)
    fit0 = np.linalg.norm(x0[:n_front] - vertices[:n_front], axis=1) * 1000

    report = {
        "sequence": os.path.abspath(seq), "object": obj, "source": src, "target": tgt,
        "frames": args.frames, "target_mask": args.target_mask, "target_mask_pixels": int(mask1.sum()),
        "stride": args.stride, "thickness_m": args.thickness,
        "youngs_modulus": args.youngs_modulus, "poisson_ratio": args.poisson_ratio, "set": args.set,
        "vertices": int(len(vertices)), "tetrahedra": int(len(tets)),
        "truth_pixels": int(len(tv)), "truth_pixels_in_slab_cells": int(c.sum()),
        "register_seconds": round(seconds, 2),
        "epe_mm": {"mean": float(epe.mean()), "median": float(np.median(epe)),
                   "p90": float(np.percentile(epe, 90))},
        "epe_in_cells_mm": {"mean": float(epe[c].mean()), "median": float(np.median(epe[c]))},
        "floor_mm": {"pixels": int(floor_ok.sum()), "mean": float(floor.mean()), "median": float(np.median(floor))},
        "start": args.start, "at_start_mm": {"mean": float(at_start.mean()), "median": float(np.median(at_start)),
                                             "along_ray_mean": float(start_along.mean()),
                                             "across_ray_mean": float(start_across.mean())},
        "still_mm": {"mean": float(still.mean()), "median": float(np.median(still)),
                     "p90": float(np.percentile(still, 90))},
        "epe_along_ray_mm": {"mean": float(epe_along.mean()), "median": float(np.median(epe_along))},
        "epe_across_ray_mm": {"mean": float(epe_across.mean()), "median": float(np.median(epe_across))},
        "still_along_ray_mm": {"mean": float(still_along.mean()), "median": float(np.median(still_along))},
        "still_across_ray_mm": {"mean": float(still_across.mean()), "median": float(np.median(still_across))},
        "frame0_front_shift_mm": {"mean": float(fit0.mean()), "max": float(fit0.max())},
        "command": " ".join(cmd),
    }
    with open(os.path.join(args.out, "report.json"), "w") as f:
        json.dump(report, f, indent=1)
    print(f"{os.path.basename(os.path.normpath(seq))} {obj} {src}->{tgt}, frames {args.frames}, target mask {args.target_mask}: "
          f"{report['vertices']} vertices, {report['tetrahedra']} tetrahedra; {len(tv)} pixels with truth")
    print(f"end-point error (mm): mean {report['epe_mm']['mean']:.1f}, median {report['epe_mm']['median']:.1f}, "
          f"90% {report['epe_mm']['p90']:.1f}; doing nothing: mean {report['still_mm']['mean']:.1f}, "
          f"median {report['still_mm']['median']:.1f}")
    if args.start != "slab":
        print(f"  at the start ({args.start}): mean {at_start.mean():.1f}, median {np.median(at_start):.1f}; "
              f"along the rays {start_along.mean():.1f}, across {start_across.mean():.1f}")
    print(f"  the slab's floor (its front vertices moved by the true flow): mean {floor.mean():.1f}, "
          f"median {np.median(floor):.1f} over {floor_ok.sum()} pixels")
    print(f"  along the camera rays: mean {epe_along.mean():.1f} (doing nothing {still_along.mean():.1f}); "
          f"across them: mean {epe_across.mean():.1f} (doing nothing {still_across.mean():.1f})")
    print(f"femreg register: {seconds:.2f} s for {expected} frame(s) (one thread); frame {src}'s front moved "
          f"{report['frame0_front_shift_mm']['mean']:.2f} mm on average from the slab as built")


if __name__ == "__main__":
    main()
