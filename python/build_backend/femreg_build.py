"""PEP 517 build backend for femreg: CMake builds the package, the standard library packs it.

No build requirement is downloaded (pyproject.toml lists none): `pip install .` works
offline with Debian's packages (scikit-build-core is not in Debian 12). The backend

  1. configures the repository with CMake (Release, tests and tools off, the Python module
     on, for the interpreter running pip; ccache as the compiler launcher when present),
  2. builds the module target (`femreg_python`, which builds libfemreg),
  3. installs the CMake component "python" (the package folder: __init__.py, the module and
     libfemreg with an $ORIGIN rpath) into a staging folder,
  4. writes that folder as a wheel (zip with METADATA, WHEEL and RECORD).

Editable installs (`pip install -e .`, PEP 660) do steps 1 and 2 only and install no copy:
the wheel holds a .pth file and a small import hook (_femreg_editable.py) that make
`import femreg` load the package from the source folder python/femreg and its compiled
module _femreg from the CMake build folder. Edits to the Python files act at once; after a
C++ change rebuild the module in that folder (`cmake --build build/python-wheel --target
femreg_python`) or run the pip command again. The build folder must stay where it is. A
femreg earlier on sys.path (PYTHONPATH, the working folder) wins over the editable one, as
it would over an installed copy.

The version is read from the project(femreg VERSION x.y.z) line of CMakeLists.txt, the one
place it is written (the module reports the same as femreg.__version__).

Settings (environment): FEMREG_WHEEL_BUILD_DIR (default build/python-wheel in the source
tree, kept between builds so a rebuild is incremental; also the editable install's build),
FEMREG_WHEEL_JOBS (parallel build jobs, default the CPU count), FEMREG_CMAKE_ARGS (extra
arguments to the configure step).
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


def _build_dir():
    return pathlib.Path(os.environ.get("FEMREG_WHEEL_BUILD_DIR",
                                       SOURCE_DIR / "build" / "python-wheel")).resolve()


def _build(build_dir):
    """Configures and builds the module target (and libfemreg) in build_dir."""
    if shutil.which("cmake") is None:
        raise RuntimeError("femreg: cmake is not installed (run tools/setup.sh as root)")
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


def _build_and_stage(stage):
    """Builds with CMake and installs the package folder into stage/femreg."""
    build_dir = _build_dir()
    _build(build_dir)
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


def _editable_finder(source, built):
    """The import hook of an editable install: femreg from source, _femreg from built."""
    return f'''"""femreg installed in editable mode (pip install -e; made by femreg_build.py).

The package is the source folder SOURCE; its compiled module _femreg is found in BUILT, the
CMake build folder. After a C++ change: cmake --build <that build folder> --target
femreg_python.
"""
import importlib.abc
import importlib.util
import os
import sys

NAME = {NAME!r}
SOURCE = {str(source)!r}
BUILT = {str(built)!r}
_SITE = os.path.dirname(os.path.realpath(__file__))


class _Finder(importlib.abc.MetaPathFinder):
    def find_spec(self, fullname, path=None, target=None):
        if fullname != NAME:
            return None
        # Where an installed copy would be: a femreg in a sys.path entry before this site
        # folder (PYTHONPATH, the working folder) wins, and this one wins over later entries.
        for entry in sys.path:
            folder = os.path.realpath(entry or os.getcwd())
            if folder == _SITE:
                break
            if os.path.isfile(os.path.join(folder, NAME, "__init__.py")):
                return None
        return importlib.util.spec_from_file_location(
            NAME, os.path.join(SOURCE, "__init__.py"), submodule_search_locations=[SOURCE, BUILT])


def install():
    if not any(isinstance(finder, _Finder) for finder in sys.meta_path):
        sys.meta_path.insert(0, _Finder())
'''


def _write_wheel(wheel_directory, files):
    """Writes files ({arcname: (bytes, mode)}) and the dist-info as the wheel; its name."""
    wheel_name = f"{NAME}-{_version()}-{_tag()}.whl"
    records = []
    target = pathlib.Path(wheel_directory) / wheel_name
    partial = target.with_suffix(".part")
    with zipfile.ZipFile(partial, "w", compression=zipfile.ZIP_DEFLATED) as wheel:
        for arcname, (data, mode) in files.items():
            info = zipfile.ZipInfo(arcname)
            info.external_attr = mode << 16
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
    with tempfile.TemporaryDirectory(prefix="femreg-wheel-") as stage:
        package = _build_and_stage(stage)
        files = {}
        for path in sorted(package.rglob("*")):
            if path.is_dir() or path.name.endswith(".pyc"):
                continue
            # libfemreg.so.0 may be a symlink in the staging folder: store its contents.
            mode = 0o755 if path.suffix == ".so" or ".so." in path.name else 0o644
            files[f"{NAME}/{path.relative_to(package).as_posix()}"] = (path.read_bytes(), mode)
        return _write_wheel(wheel_directory, files)


# ---- PEP 660 hooks (pip install -e) -----------------------------------------------------

def get_requires_for_build_editable(config_settings=None):
    return []


def prepare_metadata_for_build_editable(metadata_directory, config_settings=None):
    return prepare_metadata_for_build_wheel(metadata_directory, config_settings)


def build_editable(wheel_directory, config_settings=None, metadata_directory=None):
    """A wheel that points at the source package and the module built in the build folder."""
    build_dir = _build_dir()
    _build(build_dir)
    source = SOURCE_DIR / "python" / NAME
    built = build_dir / "python" / NAME
    if not list(built.glob("_femreg*.so")):
        raise RuntimeError(f"femreg: the CMake build did not produce {built}/_femreg*.so "
                           "(is pybind11-dev installed? see the configure output above)")
    files = {
        "_femreg_editable.py": (_editable_finder(source, built).encode(), 0o644),
        f"__editable__.{NAME}-{_version()}.pth": (b"import _femreg_editable; "
                                                  b"_femreg_editable.install()\n", 0o644),
    }
    return _write_wheel(wheel_directory, files)


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
