"""Depth images from Python: PNG round trip, back-projection, masks, tracking a depth frame."""
import numpy as np
import pytest

import femreg


def test_depth_png_round_trip(tmp_path):
    depth = (np.arange(12 * 9, dtype=np.uint32).reshape(9, 12) * 607 % 65536).astype(np.uint16)
    path = tmp_path / "d.png"
    femreg.write_depth_png(str(path), depth)
    back = femreg.read_depth_png(str(path))
    assert back.dtype == np.uint16 and back.shape == (9, 12)
    np.testing.assert_array_equal(back, depth)  # integers: exact


def test_depth_errors(tmp_path):
    bad = tmp_path / "bad.png"
    bad.write_bytes(b"not a png at all")
    with pytest.raises(femreg.Error, match="bad.png: not a PNG file"):
        femreg.read_depth_png(str(bad))
    with pytest.raises(ValueError, match=r"\(H, W\)"):
        femreg.depth_to_points(np.zeros(5, np.uint16), femreg.CameraOptions())
    with pytest.raises(ValueError, match="depth_scale"):
        femreg.depth_to_points(np.zeros((480, 640), np.uint16), femreg.CameraOptions(),
                               depth_scale=-1)
    with pytest.raises(femreg.Error, match="the camera 640x480"):
        femreg.depth_to_points(np.zeros((4, 4), np.uint16), femreg.CameraOptions())


def test_back_projection_lies_on_the_pixel_rays():
    camera = femreg.CameraOptions()
    camera.position = [0.0, 0.0, 1.0]
    camera.target = [0.0, 0.0, 0.0]   # looking down -z
    camera.up = [0.0, 1.0, 0.0]
    depth = np.zeros((camera.height, camera.width), np.uint16)
    depth[239, 319] = 500            # the pixel next to the principal point (319.5, 239.5)
    depth[0, 0] = 1000
    points = femreg.depth_to_points(depth, camera)
    assert points.shape == (2, 3)
    # Row-major order: (0, 0) first. Its depth is 1 m along the axis, so it lies on the
    # plane z = 0; the other one at 0.5 m, half a pixel's footprint (0.5 px * 0.5 m / fx)
    # off the axis towards the image's left (world -x: image x = y cross z = +x here) and
    # top (world +y, the `up`).
    np.testing.assert_allclose(points[0, 2], 0.0, atol=1e-12)
    step = 0.5 * 0.5 / 525.0
    np.testing.assert_allclose(points[1], [-step, step, 0.5], rtol=0, atol=1e-12)
    mask = np.ones_like(depth, dtype=bool)
    mask[0, 0] = False
    assert femreg.depth_to_points(depth, camera, mask=mask).shape == (1, 3)
    assert femreg.depth_to_points(depth, camera, max_depth=0.8).shape == (1, 3)


def test_tracking_a_depth_frame_equals_tracking_its_points(datasets):
    scene = femreg.load_scene(str(datasets / "demo" / "scene.yaml"))
    camera = scene.registration.camera
    path = datasets / "demo" / "depth" / "frame_0000.png"
    cloud = femreg.read_depth_frame(str(path), camera)
    depth = femreg.read_depth_png(str(path))
    np.testing.assert_array_equal(femreg.depth_to_points(depth, camera), cloud.points)
    a = femreg.Tracker(scene)
    b = femreg.Tracker(scene)
    xa = a.track_depth(depth)
    xb = b.track(cloud.points)
    # The same points in the same order: the same frame, bit for bit.
    np.testing.assert_array_equal(xa, xb)
    assert a.summary["points_used"] == b.summary["points_used"] > 1000
