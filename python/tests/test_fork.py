"""Python's multiprocessing forks (the default start method on Linux) a process that has
already tracked frames on several threads: a forked child has only the forking thread, and
femreg's worker pool and OpenMP's threads start anew there instead of waiting for the parent's.
A hang is the failure (a bounded wait, not a timing)."""
import multiprocessing

import numpy as np
import pytest

import femreg

BAR = ("objects:\n  - name: bar\n    generate: {shape: box, size: [0.2, 0.04, 0.04], cells: [20, 4, 4]}\n"
       "    material: {youngs_modulus: 1e5, poisson_ratio: 0.3, density: 1000}\n")


def track_once(threads=2):
    """One frame of the bar, seen half and lifted 1 mm, on `threads` threads: its displacement."""
    scene = femreg.parse_scene(BAR)
    scene.registration.solver.num_threads = threads
    tracker = femreg.Tracker(scene)
    rest = tracker.mesh(0).rest
    tracker.track(rest[rest[:, 0] < 0.1] + [0.0, 0.0, 0.001])
    return tracker.mesh(0).x - rest


@pytest.mark.skipif("fork" not in multiprocessing.get_all_start_methods(), reason="no fork here")
def test_forked_children_track_on_several_threads():
    parent = track_once()                 # the parent's workers and OpenMP threads exist now
    context = multiprocessing.get_context("fork")
    with context.Pool(2) as pool:
        children = pool.map_async(track_once, [2, 2, 2], chunksize=1).get(timeout=300)
    for child in children:
        assert np.allclose(child, parent, rtol=0, atol=1e-12)
    assert np.allclose(track_once(), parent, rtol=0, atol=1e-12)  # and the parent still tracks
