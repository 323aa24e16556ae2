"""Shared fixtures: where the repository and the femreg command line are."""
import importlib.util
import os
import pathlib

import pytest

SOURCE_DIR = pathlib.Path(
    os.environ.get("FEMREG_SOURCE_DIR", pathlib.Path(__file__).resolve().parents[2]))


@pytest.fixture(scope="session")
def source_dir():
    return SOURCE_DIR


@pytest.fixture(scope="session")
def datasets():
    return SOURCE_DIR / "datasets"


@pytest.fixture(scope="session")
def femreg_cli():
    """The femreg executable (CTest passes it in FEMREG_CLI)."""
    cli = os.environ.get("FEMREG_CLI")
    if not cli:
        candidate = SOURCE_DIR / "build" / "femreg"
        cli = str(candidate) if candidate.exists() else None
    if not cli or not os.path.exists(cli):
        pytest.fail("the femreg command line is needed: set FEMREG_CLI (CTest does)")
    return cli


def load_tool(name):
    """A script of tools/ as a module (tools/NAME.py), for the tests of its functions."""
    spec = importlib.util.spec_from_file_location(name, SOURCE_DIR / "tools" / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module
