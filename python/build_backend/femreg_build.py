"""PEP 517 build backend for femreg: CMake builds the package, the standard library packs it.

No build requirement is downloaded (pyproject.toml lists none): `pip install .` works
offline with Debian's packages (scikit-build-core is not in Debian 12). The backend

  1. configures the repository with CMake (Release, tests and tools off, the Python module
     on, for the interpreter running pip; ccache as the compiler launcher when present),
  2. builds the module target (`femreg_python`, which builds libfemreg),
  3. installs the CMake component "python" (the package folder: __init__.py, the module and
     libfemreg with an $ORIGIN rpath) into a staging folder,
  4. writes that folder as a wheel (zip with METADATA, WHEEL and RECORD).

Settings (environment): FEMREG_WHEEL_BUILD_DIR (default build/python-wheel in the source
tree, kept between builds so a rebuild is incremental), FEMREG_WHEEL_JOBS (parallel build
jobs, default the CPU count), FEMREG_CMAKE_ARGS (extra arguments to the configure step).
"""

import base64
import csv
import hashlib
import io
import os
import pathlib
import re
import shlex
import shutil
import subprocess
import sys
import sysconfig
import tempfile
import zipfile

SOURCE_DIR = pathlib.Path(__file__).resolve().parents[2]
NAME = "femreg"


def _version():
    text = (SOURCE_DIR / "CMakeLists.txt").read_text()
    match = re.search(r"project\(femreg\s+VERSION\s+([0-9.]+)", text)
    if not match:
        raise RuntimeError("CMakeLists.txt: no 'project(femreg VERSION x.y.z)'")
    return match.group(1)


def _tag():
    """The wheel's compatibility tag for the running interpreter, e.g. cp311-cp311-linux_x86_64."""
    impl = "cp" if sys.implementation.name == "cpython" else sys.implementation.name[:2]
    version = f"{sys.version_info.major}{sys.version_info.minor}"
    abi = f"{impl}{version}{getattr(sys, 'abiflags', '')}"
    platform = sysconfig.get_platform().replace("-", "_").replace(".", "_")
    return f"{impl}{version}-{abi}-{platform}"


def _metadata():
    readme = (SOURCE_DIR / "README.md").read_text(encoding="utf-8")
    return (
        "Metadata-Version: 2.1\n"
        f"Name: {NAME}\n"
        f"Version: {_version()}\n"
        "Summary: Physics-regularized non-rigid registration of tetrahedral meshes to point "
        "clouds and depth images\n"
        "Requires-Python: >=3.8\n"
        "Requires-Dist: numpy\n"
        "Description-Content-Type: text/markdown\n"
        "\n" + readme)


def _run(command, **kwargs):
    print("femreg_build:", " ".join(shlex.quote(str(c)) for c in command), flush=True)
    subprocess.run([str(c) for c in command], check=True, **kwargs)


def _build_and_stage(stage):
    """Builds with CMake and installs the package folder into stage/femreg."""
    if shutil.which("cmake") is None:
        raise RuntimeError("femreg: cmake is not installed (run tools/setup.sh as root)")
    build_dir = pathlib.Path(os.environ.get("FEMREG_WHEEL_BUILD_DIR",
                                            SOURCE_DIR / "build" / "python-wheel"))
    jobs = os.environ.get("FEMREG_WHEEL_JOBS", str(os.cpu_count() or 1))
    configure = ["cmake", "-S", SOURCE_DIR, "-B", build_dir, "-DCMAKE_BUILD_TYPE=Release",
                 "-DFEMREG_BUILD_TESTS=OFF", "-DFEMREG_BUILD_TOOLS=OFF",
                 "-DFEMREG_BUILD_PYTHON=ON", f"-DPython_EXECUTABLE={sys.executable}",
                 "-DFEMREG_PYTHON_INSTALL_DIR=."]
    if shutil.which("ccache"):
        configure.append("-DCMAKE_CXX_COMPILER_LAUNCHER=ccache")
    configure += shlex.split(os.environ.get("FEMREG_CMAKE_ARGS", ""))
    _run(configure)
    _run(["cmake", "--build", build_dir, "--target", "femreg_python", "-j", jobs])
    _run(["cmake", "--install", build_dir, "--component", "python", "--prefix", stage])
    package = pathlib.Path(stage) / NAME
    if not (package / "__init__.py").exists() or not list(package.glob("_femreg*.so")):
        raise RuntimeError(f"femreg: the CMake install did not produce {package}/_femreg*.so "
                           "(is pybind11-dev installed? see the configure output above)")
    return package


def _record_line(arcname, data):
    digest = base64.urlsafe_b64encode(hashlib.sha256(data).digest()).rstrip(b"=").decode()
    return [arcname, f"sha256={digest}", str(len(data))]


def _dist_info_name():
    return f"{NAME}-{_version()}.dist-info"


def _dist_info_files():
    wheel = ("Wheel-Version: 1.0\n"
             "Generator: femreg_build\n"
             "Root-Is-Purelib: false\n"
             f"Tag: {_tag()}\n")
    return {"METADATA": _metadata().encode(), "WHEEL": wheel.encode()}


# ---- PEP 517 hooks ----------------------------------------------------------------------

def get_requires_for_build_wheel(config_settings=None):
    return []


def get_requires_for_build_sdist(config_settings=None):
    return []


def prepare_metadata_for_build_wheel(metadata_directory, config_settings=None):
    info = pathlib.Path(metadata_directory) / _dist_info_name()
    info.mkdir(parents=True, exist_ok=True)
    for name, data in _dist_info_files().items():
        (info / name).write_bytes(data)
    return info.name


def build_wheel(wheel_directory, config_settings=None, metadata_directory=None):
    wheel_name = f"{NAME}-{_version()}-{_tag()}.whl"
    with tempfile.TemporaryDirectory(prefix="femreg-wheel-") as stage:
        package = _build_and_stage(stage)
        records = []
        target = pathlib.Path(wheel_directory) / wheel_name
        partial = target.with_suffix(".part")
        with zipfile.ZipFile(partial, "w", compression=zipfile.ZIP_DEFLATED) as wheel:
            for path in sorted(package.rglob("*")):
                if path.is_dir() or path.name.endswith(".pyc"):
                    continue
                # libfemreg.so.0 may be a symlink in the staging folder: store its contents.
                data = path.read_bytes()
                arcname = f"{NAME}/{path.relative_to(package).as_posix()}"
                info = zipfile.ZipInfo(arcname)
                info.external_attr = (0o755 if path.suffix == ".so" or ".so." in path.name
                                      else 0o644) << 16
                info.compress_type = zipfile.ZIP_DEFLATED
                wheel.writestr(info, data)
                records.append(_record_line(arcname, data))
            dist_info = _dist_info_name()
            for name, data in _dist_info_files().items():
                wheel.writestr(f"{dist_info}/{name}", data)
                records.append(_record_line(f"{dist_info}/{name}", data))
            out = io.StringIO()
            writer = csv.writer(out, lineterminator="\n")
            writer.writerows(records)
            writer.writerow([f"{dist_info}/RECORD", "", ""])
            wheel.writestr(f"{dist_info}/RECORD", out.getvalue())
        os.replace(partial, target)  # no half-written wheel under the final name
    return wheel_name


def build_sdist(sdist_directory, config_settings=None):
    """The tracked files of the repository (git ls-files) as NAME-VERSION.tar.gz."""
    import tarfile
    files = subprocess.run(["git", "-C", str(SOURCE_DIR), "ls-files", "-z"], check=True,
                           capture_output=True).stdout.decode().split("\0")
    base = f"{NAME}-{_version()}"
    name = f"{base}.tar.gz"
    with tarfile.open(pathlib.Path(sdist_directory) / name, "w:gz") as tar:
        for f in filter(None, files):
            tar.add(SOURCE_DIR / f, arcname=f"{base}/{f}", recursive=False)
        pkg_info = _metadata().encode()
        info = tarfile.TarInfo(f"{base}/PKG-INFO")
        info.size = len(pkg_info)
        tar.addfile(info, io.BytesIO(pkg_info))
    return name
