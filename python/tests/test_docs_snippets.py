"""The Python examples of the documentation run as written.

Every ```python block of the pages below is executed, in order, from a scratch folder that
sees the repository's datasets/ (the examples use the bundled demo), so that the docs cannot
drift from the API; a block that imports Open3D is skipped when Open3D is not installed. A block that should not run is not written as ```python. The complete
script the Python guide includes, examples/track.py, runs on the demo too.
"""
import re
import subprocess
import sys

import pytest

from conftest import SOURCE_DIR

PAGES = ["docs/guide/python.md", "docs/guide/depth-images.md"]
FENCE = re.compile(r"^```python\n(.*?)^```", re.MULTILINE | re.DOTALL)


def snippets():
    """(page, line, code) of every block; a block contained in one already listed (a shorter
    copy of another page's) is not run twice."""
    seen = []
    for page in PAGES:
        text = (SOURCE_DIR / page).read_text(encoding="utf-8")
        for match in FENCE.finditer(text):
            code = match.group(1)
            if any(code.strip() in earlier for earlier in seen):
                continue
            seen.append(code)
            line = text.count("\n", 0, match.start()) + 2
            yield pytest.param(page, line, code, id=f"{page}:{line}")


def test_pages_have_python_examples():
    assert sum(1 for _ in snippets()) >= 2


@pytest.mark.parametrize("page, line, code", list(snippets()))
def test_snippet_runs(page, line, code, tmp_path, monkeypatch):
    if "import open3d" in code:  # the Open3D examples need Open3D, which femreg does not
        pytest.importorskip("open3d", reason="Open3D is not installed (optional; Debian: "
                            "apt-get install python3-open3d)")
    (tmp_path / "datasets").symlink_to(SOURCE_DIR / "datasets")
    monkeypatch.chdir(tmp_path)
    exec(compile(code, f"{SOURCE_DIR / page}:{line}", "exec"), {"__name__": "__docs__"})


def test_track_example_runs(tmp_path):
    """examples/track.py, which the Python guide shows whole, runs on the demo."""
    out = tmp_path / "out"
    subprocess.run([sys.executable, str(SOURCE_DIR / "examples" / "track.py"),
                    str(SOURCE_DIR / "datasets" / "demo" / "scene.yaml"),
                    str(SOURCE_DIR / "datasets" / "demo" / "clouds"),
                    "--ground-truth", str(SOURCE_DIR / "datasets" / "demo" / "ground_truth"),
                    "--out", str(out)], check=True, capture_output=True, timeout=300)
    assert (out / "summary.csv").exists()
