"""tools/subdivide_surface.py, which makes the embedded-surface benchmarks' scans: its sqrt(3)
subdivision keeps a closed, consistently oriented surface and gives 3x the triangles."""
import numpy as np
import pytest

from conftest import load_tool


@pytest.fixture(scope="module")
def subdivide():
    return load_tool("subdivide_surface")


def octahedron():
    v = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], dtype=float)
    f = np.array([[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]])
    return v, f


def volume(v, f):
    a, b, c = v[f[:, 0]], v[f[:, 1]], v[f[:, 2]]
    return np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0


def check_closed(f):
    # Every directed edge once, and its reverse once: closed, manifold, consistently oriented.
    directed = np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]])
    keys = {tuple(e) for e in directed}
    assert len(keys) == len(directed)
    assert all((b, a) in keys for a, b in keys)


def test_sqrt3_triples_the_triangles_and_keeps_the_surface_closed(subdivide):
    v, f = octahedron()
    for level in range(3):
        nv, nf = len(v), len(f)
        v, f = subdivide.sqrt3(v, f)
        assert len(f) == 3 * nf
        assert len(v) == nv + nf
        check_closed(f)
        assert volume(v, f) > 0  # outward, as the octahedron
    # An approximating scheme: the vertices stay inside the octahedron (convex combinations) and
    # the corners are rounded off towards a smooth, nearly round limit surface.
    assert np.abs(v).sum(axis=1).max() <= 1.0 + 1e-12
    radius = np.linalg.norm(v, axis=1)
    assert radius.max() / radius.min() < 1.05


def test_loop_then_sqrt3_counts(subdivide):
    v, f = octahedron()
    v, f = subdivide.loop(v, f)
    v, f = subdivide.sqrt3(v, f)
    assert len(f) == 8 * 4 * 3
    check_closed(f)


def test_sqrt3_refuses_an_open_surface(subdivide):
    v, f = octahedron()
    with pytest.raises(SystemExit):
        subdivide.sqrt3(v, f[:-1])
