"""tools/hand_press_report.py's shape error: the error left after the best rigid fit of the
tracked vertices onto the true ones, which separates a wrong shape from a wrong pose."""
import numpy as np
import pytest

from conftest import load_tool


@pytest.fixture(scope="module")
def report():
    return load_tool("hand_press_report")


def rotation(axis, angle):
    axis = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + np.sin(angle) * k + (1 - np.cos(angle)) * k @ k


def test_a_turned_and_moved_copy_has_no_shape_error(report):
    truth = np.random.default_rng(3).normal(size=(200, 3)) * 0.05
    x = truth @ rotation([1, 2, 0.5], 0.4).T + [0.01, -0.02, 0.03]
    assert np.linalg.norm(x - truth, axis=1).mean() > 0.01
    assert report.rigid_fit_error(x, truth).max() < 1e-12


def test_a_squashed_copy_keeps_its_shape_error(report):
    truth = np.random.default_rng(4).normal(size=(200, 3)) * 0.05
    squashed = truth * [1.1, 1.1, 0.8]
    moved = squashed @ rotation([0, 1, 0], 0.3).T + [0.0, 0.0, 0.02]
    direct = report.rigid_fit_error(squashed, truth).mean()
    assert direct > 1e-3
    assert report.rigid_fit_error(moved, truth).mean() == pytest.approx(direct, rel=1e-9)
