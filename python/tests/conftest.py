"""Shared fixtures: where the repository and the femreg command line are."""
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
