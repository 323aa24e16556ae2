#!/usr/bin/env python3
"""Track a sequence with Open3D's data types and watch the tracked mesh over the cloud in
Open3D's viewer.

    python3 examples/open3d_view.py                        # the bundled demo, in a window
    python3 examples/open3d_view.py --clouds               # its PCD clouds instead
    python3 examples/open3d_view.py --no-window --out /tmp/o3d   # headless: PLY files

Needs Open3D (Debian: apt-get install python3-open3d); femreg itself does not. Depth frames
(a folder of PNGs, or a TUM RGB-D sequence, whose colour images colour the cloud) are read
with Open3D and handed to the tracker as open3d.geometry.RGBDImage; with --clouds, clouds
read by o3d.io.read_point_cloud are handed to it as open3d.geometry.PointCloud. The window
shows the tracked surface (grey, or coloured by the error against --ground-truth: blue 0,
red 5 mm and more) over the frame's points, seen from the scene's camera; close it to end. --no-window runs the same
without a window (for scripts and tests) and, with --out, writes the last frame's mesh and
cloud as PLY files that Open3D or MeshLab open.
"""
import argparse
import pathlib
import sys
import time

import numpy as np

import femreg

try:
    import open3d as o3d
except ImportError:
    sys.exit("open3d_view.py: needs Open3D (Debian: apt-get install python3-open3d)")

ROOT = pathlib.Path(__file__).resolve().parents[1]
DEMO = ROOT / "datasets" / "demo"


def colour_image(path, shape):
    """The frame's colour image (a TUM sequence's rgb/ file), or a grey one of `shape`."""
    if path and pathlib.Path(path).exists():
        image = o3d.io.read_image(str(path))
        if np.asarray(image).shape[:2] == shape:
            return image
    return o3d.geometry.Image(np.full(shape + (3,), 160, np.uint8))


def error_colours(errors_mm):
    """Blue (0 mm) to red (5 mm and more), per vertex."""
    t = np.clip(errors_mm / 5.0, 0.0, 1.0)[:, None]
    return (1 - t) * np.array([0.2, 0.3, 0.9]) + t * np.array([0.9, 0.1, 0.1])


def look_from(window, camera):
    """Points the viewer's camera like the scene's (femreg's camera frame: x right, y down, z
    along the optical axis, Open3D's too); the mouse turns it from there."""
    z = np.asarray(camera.target, float) - np.asarray(camera.position, float)
    z /= np.linalg.norm(z)
    up = np.asarray(camera.up, float)
    y = -(up - up.dot(z) * z)
    y /= np.linalg.norm(y)
    rotation = np.stack([np.cross(y, z), y, z])           # world to camera, by rows
    control = window.get_view_control()
    params = control.convert_to_pinhole_camera_parameters()
    extrinsic = np.eye(4)
    extrinsic[:3, :3] = rotation
    extrinsic[:3, 3] = -rotation @ np.asarray(camera.position, float)
    params.extrinsic = extrinsic
    control.convert_from_pinhole_camera_parameters(params, True)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scene", default=str(DEMO / "scene.yaml"), help="scene file (YAML)")
    parser.add_argument("--frames", help="depth frames: a folder of PNGs or a TUM RGB-D sequence "
                        "(default: the demo's depth/, or clouds/ with --clouds)")
    parser.add_argument("--clouds", action="store_true", help="read clouds (.pcd, .ply) instead")
    parser.add_argument("--depth-scale", type=float,
                        help="metres per depth unit (default: TUM's 1/5000 for a TUM sequence, else 0.001)")
    parser.add_argument("--ground-truth", help="folder of frame_NNNN.csv (default: the demo's, "
                        "when tracking the demo)")
    parser.add_argument("--max-frames", type=int, default=0, help="track only the first N frames")
    parser.add_argument("--no-window", action="store_true", help="no viewer (headless)")
    parser.add_argument("--out", help="with --no-window: write mesh.ply and cloud.ply of the last frame here")
    parser.add_argument("--delay", type=float, default=0.05, help="seconds between frames in the window")
    args = parser.parse_args()

    frames_path = args.frames or str(DEMO / ("clouds" if args.clouds else "depth"))
    truth_dir = args.ground_truth or (str(DEMO / "ground_truth") if args.frames is None else None)
    try:
        scene = femreg.load_scene(args.scene)
        tracker = femreg.Tracker(scene)
        files, info = femreg.list_frames(frames_path)   # a TUM sequence in its list's order
        tum = femreg.read_tum_sequence(info["tum_list"]) if info["tum_list"] else None
    except femreg.Error as error:                       # names the file and the line or key
        sys.exit(f"open3d_view.py: {error}")
    if args.max_frames > 0:
        files = files[:args.max_frames]
    depth_scale = args.depth_scale or info["depth_scale"] or 0.001
    camera = scene.registration.camera
    truth = sorted(pathlib.Path(truth_dir).glob("frame_*.csv")) if truth_dir else []

    mesh = tracker.mesh(0)
    surface = o3d.geometry.TriangleMesh(o3d.utility.Vector3dVector(np.array(mesh.x)),
                                        o3d.utility.Vector3iVector(np.array(mesh.surface, np.int32)))
    cloud = o3d.geometry.PointCloud()
    window = None
    if not args.no_window:
        window = o3d.visualization.Visualizer()
        window.create_window("femreg: tracked mesh over the cloud", 960, 720)
        window.get_render_option().mesh_show_back_face = True
        window.get_render_option().point_size = 3.0

    errors = []
    for f, path in enumerate(files):
        if args.clouds:
            frame = o3d.io.read_point_cloud(path)
            x = tracker.track(frame)                    # an open3d.geometry.PointCloud as it is
            cloud.points = frame.points
            cloud.paint_uniform_color([0.1, 0.6, 0.2])
        else:
            depth = o3d.io.read_image(path)
            shape = np.asarray(depth).shape[:2]
            rgb = tum.frames[f].rgb if tum else None
            rgbd = o3d.geometry.RGBDImage.create_from_color_and_depth(
                colour_image(rgb, shape), depth, depth_scale=1.0 / depth_scale, depth_trunc=100.0,
                convert_rgb_to_intensity=False)
            x = tracker.track_depth(rgbd)              # float metres through the scene's camera
            valid = np.asarray(rgbd.depth) > 0
            cloud.points = o3d.utility.Vector3dVector(femreg.depth_to_points(rgbd, camera))
            cloud.colors = o3d.utility.Vector3dVector(np.asarray(rgbd.color)[valid] / 255.0)
        surface.vertices = o3d.utility.Vector3dVector(x)
        surface.compute_vertex_normals()
        s = tracker.summary
        line = (f"frame {f}: {pathlib.Path(path).name} {s['termination']} {s['points_used']} points "
                f"{1e3 * s['time_s']['total']:.0f} ms")
        if f < len(truth):
            vertex_error = 1e3 * np.linalg.norm(x - np.loadtxt(truth[f], delimiter=",", skiprows=1)[:, :3], axis=1)
            errors.append(vertex_error.mean())
            line += f" mean error {errors[-1]:.3f} mm"
            surface.vertex_colors = o3d.utility.Vector3dVector(error_colours(vertex_error))
        else:
            surface.paint_uniform_color([0.7, 0.7, 0.7])
        print(line, flush=True)
        if window is not None:
            if f == 0:
                window.add_geometry(surface)
                window.add_geometry(cloud)
                if camera.enabled:
                    look_from(window, camera)
            window.update_geometry(surface)
            window.update_geometry(cloud)
            window.poll_events()
            window.update_renderer()
            time.sleep(args.delay)

    if errors:
        print(f"mean vertex error over {len(errors)} frames: {np.mean(errors):.3f} mm")
    if window is not None:
        window.run()                                   # until the window is closed
        window.destroy_window()
    elif args.out:
        out = pathlib.Path(args.out)
        out.mkdir(parents=True, exist_ok=True)
        o3d.io.write_triangle_mesh(str(out / "mesh.ply"), surface)
        o3d.io.write_point_cloud(str(out / "cloud.ply"), cloud)
        print(f"wrote {out / 'mesh.ply'} and {out / 'cloud.ply'}")


if __name__ == "__main__":
    main()
