"""The files of depth cameras from Python, without Open3D: NumPy depth frames (as numpy.save
writes them), Open3D's intrinsics JSON (written here by the json module), TUM RGB-D
sequences and the frame lists of `femreg register`, float depth images in metres."""
import json
import subprocess
import sys

import numpy as np
import pytest

import femreg


def demo_camera(datasets):
    return femreg.load_scene(str(datasets / "demo" / "scene.yaml")).registration.camera


def test_npy_as_numpy_saves_it(tmp_path):
    metres = np.linspace(0.0, 2.0, 12, dtype=np.float32).reshape(3, 4)
    np.save(tmp_path / "m.npy", metres)
    back = femreg.read_depth_npy(str(tmp_path / "m.npy"))
    assert back.dtype == np.float32 and back.shape == (3, 4)
    np.testing.assert_array_equal(back, metres)
    units = (np.arange(12, dtype=np.uint16) * 1000).reshape(3, 4)
    np.save(tmp_path / "f.npy", np.asfortranarray(units))          # fortran_order: True
    np.testing.assert_array_equal(femreg.read_depth_npy(str(tmp_path / "f.npy")), units)
    np.save(tmp_path / "d.npy", metres.astype(np.float64))         # '<f8'
    np.testing.assert_array_equal(femreg.read_depth_npy(str(tmp_path / "d.npy")), metres)
    np.save(tmp_path / "be.npy", units.astype(">u2"))              # big-endian
    np.testing.assert_array_equal(femreg.read_depth_npy(str(tmp_path / "be.npy")), units)


def test_npy_refusals_name_the_file_and_the_field(tmp_path):
    np.save(tmp_path / "i.npy", np.zeros((3, 4), np.int32))
    with pytest.raises(femreg.Error, match=r"i\.npy: npy header: descr '<i4': a depth image is"):
        femreg.read_depth_npy(str(tmp_path / "i.npy"))
    np.save(tmp_path / "rgb.npy", np.zeros((3, 4, 3), np.float32))
    with pytest.raises(femreg.Error, match=r"rgb\.npy: npy header: shape \(3, 4, 3\)"):
        femreg.read_depth_npy(str(tmp_path / "rgb.npy"))
    np.save(tmp_path / "f4.npy", np.zeros((3, 4), np.float32))
    data = (tmp_path / "f4.npy").read_bytes()
    (tmp_path / "cut.npy").write_bytes(data[:-5])
    with pytest.raises(femreg.Error, match=r"cut\.npy: the data from byte 128 has 43 bytes.*needs 48"):
        femreg.read_depth_npy(str(tmp_path / "cut.npy"))


def test_npy_frames_back_project_like_their_pngs(datasets, tmp_path):
    camera = demo_camera(datasets)
    png = datasets / "demo" / "depth" / "frame_0000.png"
    units = femreg.read_depth_png(str(png))
    np.save(tmp_path / "units.npy", units)
    np.save(tmp_path / "metres.npy", (units * 0.001).astype(np.float32))
    reference = femreg.read_depth_frame(str(png), camera).points
    np.testing.assert_array_equal(femreg.read_frame(str(tmp_path / "units.npy"), camera).points,
                                  reference)
    np.testing.assert_allclose(femreg.read_depth_frame(str(tmp_path / "metres.npy"), camera).points,
                               reference, atol=1e-6)
    # A cloud file through the same front end.
    cloud = femreg.read_frame(str(datasets / "demo" / "clouds" / "frame_0000.pcd"), camera)
    assert len(cloud) > 1000


def test_float_depth_images_are_metres(datasets, tmp_path):
    camera = demo_camera(datasets)
    units = femreg.read_depth_png(str(datasets / "demo" / "depth" / "frame_0000.png"))
    reference = femreg.depth_to_points(units, camera)
    metres = units.astype(np.float32) * np.float32(0.001)
    np.testing.assert_allclose(femreg.depth_to_points(metres, camera), reference, atol=1e-6)
    with_nan = metres.copy()
    with_nan[with_nan == 0] = np.nan                       # NaN = no return, like 0
    assert femreg.depth_to_points(with_nan, camera).shape == reference.shape
    # A float array of millimetres is caught, not put kilometres away.
    with pytest.raises(ValueError, match="a float array holds metres, and this one reaches"):
        femreg.depth_to_points(units.astype(np.float64), camera)
    # Written as a PNG: metres to units of depth_scale.
    femreg.write_depth_png(str(tmp_path / "m.png"), metres)
    np.testing.assert_array_equal(femreg.read_depth_png(str(tmp_path / "m.png")), units)
    tracker = femreg.Tracker(femreg.load_scene(str(datasets / "demo" / "scene.yaml")))
    x = tracker.track_depth(metres)
    assert x.shape[1] == 3 and tracker.summary["points_used"] == len(reference)


def test_intrinsics_json(tmp_path):
    path = tmp_path / "camera.json"
    path.write_text(json.dumps({"width": 320, "height": 240,
                                "intrinsic_matrix": [300, 0, 0, 0, 301, 0, 159.5, 119.5, 1]}))
    posed = femreg.CameraOptions()
    posed.position = [0.0, 0.0, 1.0]
    posed.target = [0.0, 0.0, 0.0]
    posed.up = [0.0, 1.0, 0.0]
    camera = femreg.read_intrinsics(str(path), posed)
    assert (camera.fx, camera.fy, camera.cx, camera.cy) == (300, 301, 159.5, 119.5)
    assert (camera.width, camera.height) == (320, 240)
    np.testing.assert_array_equal(camera.position, [0, 0, 1])      # the pose given
    femreg.write_intrinsics(str(tmp_path / "back.json"), camera)
    written = json.loads((tmp_path / "back.json").read_text())
    assert written["intrinsic_matrix"] == [300, 0, 0, 0, 301, 0, 159.5, 119.5, 1]
    path.write_text(json.dumps({"width": 320, "height": 240,
                                "intrinsic_matrix": [300, 0, 159.5, 0, 301, 119.5, 0, 0, 1]}))
    with pytest.raises(femreg.Error, match=r"camera\.json: intrinsic_matrix: cx and cy are at \[2\]"):
        femreg.read_intrinsics(str(path))
    path.write_text('{"width": 320, "height": 240}')
    with pytest.raises(femreg.Error, match=r"camera\.json: intrinsic_matrix: missing"):
        femreg.read_intrinsics(str(path))


def test_intrinsics_matrix(tmp_path):
    """The camera matrix as numpy.savetxt writes it (DeepDeform's intrinsics.txt is the 4x4
    form): fx..cy from the file, the image size and the pose the camera's."""
    path = tmp_path / "intrinsics.txt"
    k = np.eye(4)
    k[0, 0], k[1, 1], k[0, 2], k[1, 2] = 575.548, 577.46, 323.172, 236.417
    np.savetxt(path, k)
    posed = femreg.CameraOptions()
    posed.position = [0.0, 0.0, 1.0]
    posed.width, posed.height = 320, 240
    camera = femreg.read_intrinsics(str(path), posed)
    assert (camera.fx, camera.fy, camera.cx, camera.cy) == (575.548, 577.46, 323.172, 236.417)
    assert (camera.width, camera.height) == (320, 240)
    np.testing.assert_array_equal(camera.position, [0, 0, 1])
    np.savetxt(path, k[:3, :3].T)   # transposed: cx, cy in the last row
    with pytest.raises(femreg.Error, match=r"intrinsics\.txt:3: \[2\]\[0\]: must be 0 .*transposed"):
        femreg.read_intrinsics(str(path))
    np.savetxt(path, k)
    with pytest.raises(femreg.Error, match=r"intrinsics\.txt: a camera matrix holds no image size"):
        femreg.read_intrinsics(str(path))


def make_tum(datasets, root, frames=3):
    """The demo's first frames as a TUM sequence: 5000 units per metre, depth.txt."""
    (root / "depth").mkdir(parents=True)
    lines = ["# depth maps", "# timestamp filename"]
    for f in range(frames):
        units = femreg.read_depth_png(str(datasets / "demo" / "depth" / f"frame_{f:04d}.png"))
        name = f"depth/{1305031102 + f}.5.png"
        femreg.write_depth_png(str(root / name), (units.astype(np.uint32) * 5).astype(np.uint16))
        lines.append(f"{1305031102 + f}.5 {name}")
    (root / "depth.txt").write_text("\n".join(lines) + "\n")


def test_tum_sequence_and_frame_lists(datasets, tmp_path):
    make_tum(datasets, tmp_path / "seq")
    files, info = femreg.list_frames(str(tmp_path / "seq"))
    assert info["tum_list"] == str(tmp_path / "seq" / "depth.txt")
    assert info["depth_scale"] == femreg.TUM_DEPTH_SCALE == 1 / 5000
    assert info["times"] == [1305031102.5, 1305031103.5, 1305031104.5]
    assert files == [str(tmp_path / "seq" / "depth" / f"{1305031102 + f}.5.png") for f in range(3)]
    seq = femreg.read_tum_sequence(str(tmp_path / "seq"))
    assert len(seq) == 3 and seq.frames[2].line == 5 and seq.depth_files == files
    # Tracked at TUM's scale: the demo's points.
    camera = demo_camera(datasets)
    np.testing.assert_allclose(
        femreg.read_frame(files[0], camera, depth_scale=info["depth_scale"]).points,
        femreg.read_depth_frame(str(datasets / "demo" / "depth" / "frame_0000.png"), camera).points,
        atol=1e-12)
    plain, plain_info = femreg.list_frames(str(datasets / "demo" / "depth"))
    assert len(plain) == 30 and plain_info == {"tum_list": None, "depth_scale": None, "times": None}
    with open(tmp_path / "seq" / "depth.txt", "a") as handle:
        handle.write("1305031109.5 depth/missing.png\n")
    with pytest.raises(femreg.Error, match=r"depth\.txt:6: .*depth/missing\.png: no such file"):
        femreg.list_frames(str(tmp_path / "seq"))


def test_register_reads_a_tum_sequence(datasets, tmp_path, femreg_cli):
    make_tum(datasets, tmp_path / "seq", frames=2)
    run = subprocess.run([femreg_cli, "register", "--scene", str(datasets / "demo" / "scene.yaml"),
                          "--frames", str(tmp_path / "seq"), "--out", str(tmp_path / "out"),
                          "--no-progress", "--report", "none", "--threads", "1"],
                         capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stdout + run.stderr
    assert "TUM RGB-D sequence: 2 depth frames" in run.stdout
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert summary["command_line"]["depth_scale"] == 0.0002
    assert summary["provenance"]["tum_list"] == str(tmp_path / "seq" / "depth.txt")


def test_femreg_does_not_import_open3d():
    """Open3D is optional: femreg loads it only when handed one of its objects."""
    code = ("import sys, numpy, femreg\n"
            "t = femreg.Tracker([femreg.make_box([0.1, 0.02, 0.02], [4, 1, 1])], [femreg.Material()])\n"
            "t.track(numpy.random.default_rng(0).random((50, 3)) * 0.02)\n"
            "femreg.depth_to_points(numpy.zeros((480, 640), numpy.float32), femreg.CameraOptions())\n"
            "assert 'open3d' not in sys.modules, 'open3d was imported'\n")
    subprocess.run([sys.executable, "-c", code], check=True, timeout=120)


def test_what_is_not_a_cloud_is_named():
    tracker = femreg.Tracker([femreg.make_box([0.1, 0.02, 0.02], [4, 1, 1])], [femreg.Material()])
    with pytest.raises(TypeError, match=r"points: expected an \(N, 3\) array of numbers or an "
                                        r"open3d.geometry.PointCloud \(got dict\)"):
        tracker.track({"points": []})
