"""One version, written once: CMakeLists.txt's project() line. The module, the command line,
summary.json and the build backend (the wheel's metadata) all report it."""
import json
import re
import subprocess
import sys

import femreg


def project_version(source_dir):
    text = (source_dir / "CMakeLists.txt").read_text()
    match = re.search(r"project\(femreg\s+VERSION\s+([0-9]+\.[0-9]+\.[0-9]+)", text)
    assert match, "CMakeLists.txt: no 'project(femreg VERSION x.y.z)'"
    return match.group(1)


def test_module_version_is_the_projects(source_dir):
    assert femreg.__version__ == project_version(source_dir)


def test_cli_version_is_the_projects(source_dir, femreg_cli):
    out = subprocess.run([femreg_cli, "--version"], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == f"femreg {project_version(source_dir)}"


def test_summary_json_records_the_projects_version(tmp_path, source_dir, datasets, femreg_cli):
    out = tmp_path / "sim"
    subprocess.run([femreg_cli, "simulate", str(datasets / "beam" / "beam.yaml"),
                    "--out", str(out)], check=True, stdout=subprocess.DEVNULL)
    summary = json.loads((out / "summary.json").read_text())
    assert summary["femreg_version"] == project_version(source_dir)


def test_build_backend_reads_the_same_version(source_dir, monkeypatch):
    monkeypatch.syspath_prepend(str(source_dir / "python" / "build_backend"))
    monkeypatch.delitem(sys.modules, "femreg_build", raising=False)
    import femreg_build
    assert femreg_build._version() == project_version(source_dir)
