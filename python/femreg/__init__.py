"""femreg: physics-regularized non-rigid registration from Python.

A tetrahedral mesh of a deformable object is fitted to each point cloud of a sequence by
minimizing data terms regularized by a corotational linear FEM energy (the C++ library,
through pybind11). Units are SI: metres, pascals, seconds.

    import femreg
    scene = femreg.load_scene("datasets/demo/scene.yaml")
    tracker = femreg.Tracker(scene)
    for points in clouds:               # (N, 3) float arrays, metres, scene frame
        x = tracker.track(points)       # (V, 3) vertices of object 0
        print(tracker.summary["termination"], tracker.summary["rms_residual"])

Every error of the C++ library (a bad file, a bad scene) is raised as femreg.Error with
the library's message (which names the file, line or field); bad argument shapes and
option names raise ValueError.

Open3D is optional: where a cloud is taken, an open3d.geometry.PointCloud is too, and where
a depth image is taken, an open3d.geometry.Image or RGBDImage (femreg never imports Open3D
unless it is handed one of its objects).
"""

import os as _os

# OpenMP's threads sleep between teams instead of spinning on cores other processes need,
# unless the user chose a policy or a spin count, as the command does (read once, when OpenMP
# loads: docs/guide/busy-machines.md).
if "OMP_WAIT_POLICY" not in _os.environ and "GOMP_SPINCOUNT" not in _os.environ:
    _os.environ["OMP_WAIT_POLICY"] = "passive"


def _mapped_files():
    """The files mapped into this process (None where /proc cannot tell)."""
    try:
        with open("/proc/self/maps") as maps:
            return {line.split(None, 5)[5].strip() for line in maps if len(line.split(None, 5)) == 6}
    except OSError:
        return None


# OpenBLAS takes slow generic kernels on a CPU newer than itself. femreg switches the OpenBLAS
# it uses to this CPU's kernels when its own import loaded that library (nothing else can be
# using it then; numpy's wheels bring copies of their own), and when the user did not choose
# (OPENBLAS_CORETYPE; docs/guide/busy-machines.md).
_mapped_before = _mapped_files() if "OPENBLAS_CORETYPE" not in _os.environ else None

from ._femreg import (  # noqa: E402,F401  (the public API)
    __version__,
    TUM_DEPTH_SCALE,
    CameraOptions,
    CollisionOptions,
    DataTermOptions,
    DepthSensorOptions,
    Error,
    ForwardOptions,
    FractureOptions,
    Material,
    Mesh,
    PointCloud,
    PreprocessOptions,
    RegistrationOptions,
    Scene,
    SolverOptions,
    SynthBody,
    SynthOptions,
    Tracker,
    TumFrame,
    TumSequence,
    WeightOptions,
    camera_from_open3d,
    list_frames,
    load_scene,
    make_box,
    depth_to_points,
    mesh_from_arrays,
    parse_scene,
    read_depth_frame,
    read_depth_npy,
    read_depth_png,
    read_frame,
    read_intrinsics,
    read_mesh,
    read_point_cloud,
    read_tum_sequence,
    simulate,
    write_depth_png,
    write_intrinsics,
    write_obj_surface,
    write_ply_surface,
    write_point_cloud,
    write_vtu,
    blas_kernels,
    use_better_blas_kernels,
)

from ._femreg import _blas_library  # noqa: E402


def _loaded_by_this_import(path):
    if not path or _mapped_before is None:
        return False
    real = _os.path.realpath(path)
    return not any(f == path or _os.path.realpath(f) == real for f in _mapped_before if f.startswith("/"))


if _loaded_by_this_import(_blas_library()):
    use_better_blas_kernels()
del _mapped_before
