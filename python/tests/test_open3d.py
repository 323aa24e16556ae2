"""Open3D's objects where femreg takes clouds, depth images and intrinsics, and the example
that shows the tracked mesh over the cloud in Open3D's viewer (run headless). Skipped when
Open3D is not installed: femreg does not need it (Debian: apt-get install python3-open3d)."""
import pathlib
import subprocess
import sys

import numpy as np
import pytest

import femreg
from conftest import SOURCE_DIR

o3d = pytest.importorskip(
    "open3d", reason="Open3D is not installed (optional; Debian: apt-get install python3-open3d)")


@pytest.fixture(scope="module")
def demo(datasets):
    return femreg.load_scene(str(datasets / "demo" / "scene.yaml"))


def test_point_cloud_is_taken_with_its_normals(datasets, demo):
    path = str(datasets / "demo" / "clouds" / "frame_0000.pcd")
    pcd = o3d.io.read_point_cloud(path)
    cloud, _ = femreg.read_point_cloud(path)
    np.testing.assert_array_equal(np.asarray(pcd.points), cloud.points)
    a, b = femreg.Tracker(demo), femreg.Tracker(demo)
    xa = a.track(pcd)
    xb = b.track(cloud.points, cloud.normals if pcd.has_normals() else None)
    np.testing.assert_array_equal(xa, xb)                  # the same frame, bit for bit
    assert len(femreg.PointCloud(pcd)) == len(cloud)
    pcd.estimate_normals()
    assert femreg.PointCloud(pcd).normals.shape == (len(cloud), 3)


def test_written_clouds_and_intrinsics_read_back_in_open3d(tmp_path, demo):
    pcd = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(np.random.default_rng(1).random((20, 3))))
    femreg.write_point_cloud(str(tmp_path / "c.pcd"), pcd)
    np.testing.assert_allclose(femreg.read_point_cloud(str(tmp_path / "c.pcd"))[0].points,
                               np.asarray(pcd.points), atol=1e-6)   # PCD stores float32
    intrinsic = o3d.camera.PinholeCameraIntrinsic(320, 240, 300.0, 301.0, 159.5, 119.5)
    o3d.io.write_pinhole_camera_intrinsic(str(tmp_path / "k.json"), intrinsic)
    camera = femreg.read_intrinsics(str(tmp_path / "k.json"), demo.registration.camera)
    assert (camera.fx, camera.fy, camera.cx, camera.cy, camera.width) == (300, 301, 159.5, 119.5, 320)
    np.testing.assert_array_equal(camera.position, demo.registration.camera.position)
    same = femreg.camera_from_open3d(intrinsic, demo.registration.camera)
    assert (same.fx, same.fy, same.cx, same.cy, same.height) == (300, 301, 159.5, 119.5, 240)
    femreg.write_intrinsics(str(tmp_path / "back.json"), camera)
    back = o3d.io.read_pinhole_camera_intrinsic(str(tmp_path / "back.json"))
    np.testing.assert_array_equal(back.intrinsic_matrix, intrinsic.intrinsic_matrix)
    with pytest.raises(TypeError, match="PinholeCameraIntrinsic"):
        femreg.camera_from_open3d(pcd)


def test_images_and_rgbd_images_are_depth_images(datasets, demo):
    camera = demo.registration.camera
    path = str(datasets / "demo" / "depth" / "frame_0000.png")
    units = femreg.read_depth_png(path)
    reference = femreg.depth_to_points(units, camera)
    image = o3d.io.read_image(path)                      # uint16 units
    np.testing.assert_array_equal(femreg.depth_to_points(image, camera), reference)
    colour = o3d.geometry.Image(np.zeros(units.shape + (3,), np.uint8))
    rgbd = o3d.geometry.RGBDImage.create_from_color_and_depth(
        colour, image, depth_scale=1000.0, depth_trunc=10.0, convert_rgb_to_intensity=False)
    np.testing.assert_allclose(femreg.depth_to_points(rgbd, camera), reference, atol=1e-6)  # float32 metres
    a, b = femreg.Tracker(demo), femreg.Tracker(demo)
    xa, xb = a.track_depth(rgbd), b.track_depth(units)
    assert a.summary["points_used"] == b.summary["points_used"]
    np.testing.assert_allclose(xa, xb, atol=1e-6)
    with pytest.raises(ValueError, match=r"\(H, W\)"):
        femreg.depth_to_points(colour, camera)           # a colour image is not a depth image


@pytest.mark.parametrize("mode", ["rgbd", "clouds"])
def test_viewer_example_runs_headless(mode, tmp_path):
    """examples/open3d_view.py without its window: RGBD images or Open3D clouds in, the demo's
    errors out, and the last mesh and cloud written as PLY."""
    args = [sys.executable, str(SOURCE_DIR / "examples" / "open3d_view.py"), "--no-window",
            "--max-frames", "3", "--out", str(tmp_path)]
    if mode == "clouds":
        args.append("--clouds")
    run = subprocess.run(args, capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stdout + run.stderr
    errors = [float(line.split("mean error ")[1].split()[0])
              for line in run.stdout.splitlines() if "mean error" in line]
    assert len(errors) == 3 and max(errors) < 1.0, run.stdout   # mm
    mesh = o3d.io.read_triangle_mesh(str(pathlib.Path(tmp_path) / "mesh.ply"))
    assert len(mesh.triangles) > 100 and len(o3d.io.read_point_cloud(str(tmp_path / "cloud.ply")).points) > 1000
