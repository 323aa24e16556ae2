"""The Python API: readers and writers, options, errors as exceptions, the tracker on a
small synthetic problem, the forward solve."""
import numpy as np
import pytest

import femreg


def test_error_is_raised_with_the_library_message(tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text("objects:\n  - name: a\n    generate: {shape: box}\n"
                   "    material: {poisson_ratio: 0.7}\n")
    with pytest.raises(femreg.Error) as info:
        femreg.load_scene(str(bad))
    message = str(info.value)
    # The C++ message names the file, the line and the key.
    assert "bad.yaml:4" in message
    assert "poisson_ratio" in message
    assert isinstance(info.value, RuntimeError)


def test_options_attributes_follow_the_tables():
    # Every field of a table-driven options struct is an attribute (three had none before the
    # tables), named as the scene file names it but solver.threads (num_threads), and
    # validate() names a bad one as the scene parser does.
    options = femreg.RegistrationOptions()
    assert options.data.min_points == 10
    assert options.data.min_points_per_surface_vertex == pytest.approx(0.01)
    assert options.solver.max_pcg_iterations == 20
    assert options.camera.width == 640 and not options.camera.enabled
    assert options.data.loss == "huber" and options.regularizer == "corotational"
    with pytest.raises(ValueError, match="data.loss: unknown value 'l1'"):
        options.data.loss = "l1"
    options.solver.num_threads = -1
    with pytest.raises(ValueError, match=r"solver.threads must be >= 0 .* \(got -1\)"):
        options.validate()
    # The scene key's name too; a misspelt attribute names the ones there are.
    options.solver.threads = 2
    assert options.solver.num_threads == 2
    with pytest.raises(AttributeError, match=r"SolverOptions has no attribute 'thread' \(its attributes: .*backend"):
        options.solver.thread = 1
    with pytest.raises(AttributeError, match="visibility"):
        options.data.visibilty = True


def test_scene_sections_follow_their_tables():
    # The sections beside registration: (forward, effects.fracture, collision, synth) are
    # bound from their tables too, changed in place and written back by to_yaml().
    scene = femreg.parse_scene(
        "objects: [{generate: {shape: box, size: [1, 0.1, 0.1], cells: [4, 1, 1]}}]\n"
        "forward: {load_steps: 3}\n"
        "effects: {fracture: {max_cracks: 2}}\n"
        "collision: {friction_slip: 0.0002}\n")
    assert scene.forward.load_steps == 3
    assert scene.fracture.max_cracks == 2 and scene.effects_fracture
    assert scene.collision.friction_slip == pytest.approx(2e-4)
    scene.forward.relative_tolerance = 1e-6  # the key `tolerance`
    scene.fracture.cut_through = True
    scene.collision.stiffness = 5e4
    again = femreg.parse_scene(scene.to_yaml())
    assert again.forward.relative_tolerance == pytest.approx(1e-6)
    assert again.fracture.cut_through and again.fracture.max_cracks == 2
    assert again.collision.stiffness == pytest.approx(5e4)
    assert repr(femreg.Material()) == "Material(youngs_modulus=100000.0, poisson_ratio=0.3, density=1000.0)"


def test_forward_model_is_unset_until_a_scene_or_caller_sets_it():
    # forward.model is a row of ForwardOptions' table: None until set (the corotational
    # element, and the neo-Hookean one for a nearly incompressible object); set, even to
    # corotational, it is written and read back; None unsets it again.
    scene = femreg.parse_scene("objects: [{generate: {shape: box, size: [1, 0.1, 0.1], cells: [4, 1, 1]}}]\n")
    assert scene.forward.model is None and femreg.ForwardOptions().model is None
    assert "model" not in scene.to_yaml()
    scene.forward.model = "corotational"
    assert "forward: {model: corotational}" in scene.to_yaml()
    assert femreg.parse_scene(scene.to_yaml()).forward.model == "corotational"
    with pytest.raises(ValueError, match="forward.model: unknown value 'hooke'"):
        scene.forward.model = "hooke"
    scene.forward.model = None
    assert "model" not in scene.to_yaml()


def test_material_and_synth_body_take_their_tables_fields():
    # Their constructors' keywords are their tables' rows: each defaults to the struct's
    # value, an unknown one raises TypeError naming the accepted ones, a bad value ValueError.
    m = femreg.Material(poisson_ratio=0.45, density=900)
    assert (m.youngs_modulus, m.poisson_ratio, m.density) == (1e5, 0.45, 900.0)
    assert femreg.Material(2e5).youngs_modulus == 2e5
    with pytest.raises(TypeError, match="unexpected keyword argument 'poisson'.*poisson_ratio"):
        femreg.Material(poisson=0.3)
    with pytest.raises(ValueError, match=r"Material: poisson_ratio must be in \(-1, 0.5\) \(got 0.5\)"):
        femreg.Material(poisson_ratio=0.5)
    body = femreg.SynthBody(box_min=[0, 0, 0.2], box_max=[0.1, 0.1, 0.3], press=True)
    body.name = "tool"
    assert body.press and not body.in_cloud and list(body.box_max) == pytest.approx([0.1, 0.1, 0.3])
    assert repr(body).startswith("SynthBody(box_min=[0.0, 0.0, 0.2], box_max=[0.1, 0.1, 0.3], in_cloud=False")
    with pytest.raises(ValueError, match=r"synth.bodies.contact_tolerance must be >= 0"):
        femreg.SynthBody(box_max=[1, 1, 1], contact_tolerance=-1)
    # A scene's synth section takes bodies made in Python and writes them back.
    scene = femreg.parse_scene(
        "objects: [{generate: {shape: box, size: [1, 0.1, 0.1], cells: [4, 1, 1]}}]\n"
        "registration:\n  camera: {position: [0, 0, 2], target: [0, 0, 0], up: [0, 1, 0]}\n"
        "synth:\n  ground_truth: {refinement: 2}\n"
        "  bodies: [{name: hand, box: {min: [0, 0, 0.5], max: [0.2, 0.1, 0.6]}, in_cloud: true}]\n")
    assert [b.name for b in scene.synth.bodies] == ["hand"] and scene.synth.bodies[0].in_cloud
    scene.synth.bodies = scene.synth.bodies + [body]
    again = femreg.parse_scene(scene.to_yaml())
    assert [b.name for b in again.synth.bodies] == ["hand", "tool"]
    assert again.synth.bodies[1].press and list(again.synth.bodies[1].box_min) == pytest.approx([0, 0, 0.2])


def test_missing_files_raise():
    with pytest.raises(femreg.Error, match="no_such_mesh.vtu"):
        femreg.read_mesh("no_such_mesh.vtu")
    with pytest.raises(femreg.Error, match="no_such_cloud.pcd"):
        femreg.read_point_cloud("no_such_cloud.pcd")


def test_bad_shapes_and_names_raise_value_error():
    mesh = femreg.make_box([0.1, 0.02, 0.02], [5, 1, 1])
    tracker = femreg.Tracker([mesh], [femreg.Material()])
    with pytest.raises(ValueError, match=r"points: expected an \(N, 3\) array, got shape \(4, 2\)"):
        tracker.track(np.zeros((4, 2)))
    with pytest.raises(ValueError, match="normals"):
        tracker.track(np.zeros((4, 3)), normals=np.zeros((3, 3)))
    options = femreg.RegistrationOptions()
    with pytest.raises(ValueError, match="solver.backend: unknown value 'fastest'"):
        options.solver.backend = "fastest"
    assert options.solver.preconditioner == "auto"
    options.solver.preconditioner = "multigrid"
    assert options.solver.preconditioner == "multigrid"
    with pytest.raises(ValueError, match="solver.preconditioner: unknown value 'amg'"):
        options.solver.preconditioner = "amg"
    # The first frame's pose (docs/guide/scene-files.md#initial-pose).
    assert options.initial_pose == "auto"
    options.initial_pose = "given"
    assert options.initial_pose == "given"
    with pytest.raises(ValueError, match="initial_pose: unknown value 'global'"):
        options.initial_pose = "global"
    # The model->cloud tests of partial views (docs/guide/partial-views.md).
    assert options.data.auto_visibility and options.data.reciprocity == 5.0
    options.data.reciprocity = 0.0
    assert options.data.reciprocity == 0.0
    with pytest.raises(IndexError):
        tracker.vertices(1)
    # Nothing was tracked by the failed calls.
    assert tracker.frame == 0


def test_mesh_round_trip(tmp_path):
    mesh = femreg.make_box([0.2, 0.05, 0.05], [4, 1, 1])
    assert mesh.num_vertices == 20 and mesh.num_tets == 24
    moved = mesh.rest + np.array([0.01, 0.0, 0.0])
    path = tmp_path / "box.vtu"
    femreg.write_vtu(str(path), mesh, moved,
                     fields={"displacement": moved - mesh.rest,
                             "cell_id": np.arange(mesh.num_tets, dtype=float)})
    back = femreg.read_mesh(str(path))
    # VTU stores Float64: the positions come back exactly (up to the last bit; 1e-15 m).
    np.testing.assert_allclose(back.rest, moved, rtol=0, atol=1e-15)
    np.testing.assert_array_equal(np.sort(back.tets, axis=1), np.sort(mesh.tets, axis=1))
    femreg.write_ply_surface(str(tmp_path / "s.ply"), mesh)
    femreg.write_obj_surface(str(tmp_path / "s.obj"), mesh, moved)
    assert (tmp_path / "s.obj").read_text().startswith(("#", "v "))


def test_mesh_arrays_are_read_only_views():
    mesh = femreg.make_box([1, 1, 1], [1, 1, 1])
    rest = mesh.rest
    assert rest.shape == (8, 3) and rest.dtype == np.float64
    assert not rest.flags.owndata  # a view of the C++ mesh, not a copy
    assert not rest.flags.writeable


def test_point_cloud_round_trip(tmp_path):
    rng = np.random.default_rng(3)
    points = rng.uniform(-1, 1, (50, 3))
    normals = rng.normal(size=(50, 3))
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    path = tmp_path / "c.pcd"
    femreg.write_point_cloud(str(path), points, normals)
    cloud, info = femreg.read_point_cloud(str(path))
    assert len(cloud) == 50 and info["nonfinite_dropped"] == 0
    # Binary PCD stores float32: 6e-8 relative; coordinates are <= 1 m.
    np.testing.assert_allclose(cloud.points, points, rtol=0, atol=1e-7)
    np.testing.assert_allclose(cloud.normals, normals, rtol=0, atol=1e-7)


def _surface_cloud(mesh, positions):
    """Points on every surface triangle (centroids and vertices) at `positions`."""
    tri = positions[mesh.surface]
    return np.concatenate([tri.mean(axis=1), positions[np.unique(mesh.surface)]])


def test_tracker_follows_a_rigid_translation():
    mesh = femreg.make_box([0.2, 0.04, 0.04], [10, 2, 2])
    options = femreg.RegistrationOptions()
    options.solver.max_outer_iterations = 10
    tracker = femreg.Tracker([mesh], [femreg.Material(youngs_modulus=5e4, density=200)], options)
    shift = np.array([0.004, -0.002, 0.001])
    for _ in range(4):
        x = tracker.track(_surface_cloud(mesh, mesh.rest + shift))
    assert x.shape == (mesh.num_vertices, 3)
    summary = tracker.summary
    assert summary["usable"] and summary["frame"] == 3
    assert summary["termination"] in ("converged", "max_iterations")
    assert summary["points_used"] > 0 and summary["iterations"]
    assert summary["initial_pose"] == "" and not summary["pose_ambiguous"]  # the first frame's
    # A rigid motion costs no elastic energy: the fit reaches the shifted mesh to well below
    # the 4.9 mm shift (0.1 mm: the data term's gating and temporal pull leave micrometres).
    assert np.abs(x - (mesh.rest + shift)).max() < 1e-4
    np.testing.assert_array_equal(tracker.vertices(0), x)
    assert summary["confidence"] > 0.9 and not summary["lost"]
    assert set(summary["confidence_parts"]) == {"fit", "coverage", "residual", "strain", "volume_change"}


def test_a_frame_without_the_object_is_lost_and_keeps_the_last_good_shape():
    mesh = femreg.make_box([0.2, 0.04, 0.04], [10, 2, 2])
    options = femreg.RegistrationOptions()
    assert options.data.lost_coverage == 0.3
    tracker = femreg.Tracker([mesh], [femreg.Material(youngs_modulus=5e4, density=200)], options)
    good = tracker.track(_surface_cloud(mesh, mesh.rest)).copy()
    x = tracker.track(_surface_cloud(mesh, mesh.rest + [0.5, 0.0, 0.0]))
    assert tracker.summary["lost"] and tracker.summary["confidence"] < 0.3
    np.testing.assert_array_equal(x, good)


def test_depth_offset_is_reachable():
    # registration.preprocess.depth_offset (docs/guide/depth-images.md#depth-offset): on by
    # default; without a camera and a plane it takes nothing off, and the summary says so.
    options = femreg.RegistrationOptions()
    assert options.preprocess.depth_offset
    options.preprocess.depth_offset = False
    assert not options.preprocess.depth_offset
    options.preprocess.depth_offset = True
    mesh = femreg.make_box([0.2, 0.04, 0.04], [10, 2, 2])
    tracker = femreg.Tracker([mesh], [femreg.Material(youngs_modulus=5e4, density=200)], options)
    tracker.track(_surface_cloud(mesh, mesh.rest))
    assert tracker.summary["depth_offset"] == 0.0


def test_free_space_is_reachable():
    # registration.free_space (docs/guide/partial-views.md#free-space) from Python: its options,
    # their checks, and the vertices it held in the summary (none: the model matches the cloud).
    options = femreg.RegistrationOptions()
    assert options.free_space.enabled and options.free_space.tolerance == 0.01
    assert options.free_space.weight == 1e4
    options.free_space.tolerance = 0.02
    options.free_space.weight = 5e3
    options.validate()
    mesh = femreg.make_box([0.2, 0.04, 0.04], [10, 2, 2])
    tracker = femreg.Tracker([mesh], [femreg.Material(youngs_modulus=5e4, density=200)], options)
    tracker.track(_surface_cloud(mesh, mesh.rest))
    assert tracker.summary["usable"] and tracker.summary["free_space_vertices"] == 0
    options.free_space.tolerance = 0.0
    with pytest.raises(ValueError, match="free_space.tolerance"):
        options.validate()
    options.free_space.tolerance = 0.01
    options.free_space.enabled = False
    options.validate()


def test_per_area_weights_are_reachable():
    # The per-area data weight (docs/theory/data-weight.md#per-area) from Python: weights.data < 0
    # selects it; the fit follows the same rigid translation.
    mesh = femreg.make_box([0.2, 0.04, 0.04], [10, 2, 2])
    options = femreg.RegistrationOptions()
    options.solver.max_outer_iterations = 10
    options.weights.data = -1
    options.weights.data_per_area = 1.15e7
    options.weights.model_to_cloud_share = 0.3
    options.weights.model_to_cloud_area_cap = 2
    tracker = femreg.Tracker([mesh], [femreg.Material(youngs_modulus=5e4, density=200)], options)
    shift = np.array([0.004, -0.002, 0.001])
    for _ in range(4):
        x = tracker.track(_surface_cloud(mesh, mesh.rest + shift))
    assert tracker.summary["usable"]
    assert np.abs(x - (mesh.rest + shift)).max() < 1e-4
    options.weights.model_to_cloud_area_cap = -1
    with pytest.raises(femreg.Error, match="model_to_cloud_area_cap"):
        femreg.Tracker([mesh], [femreg.Material(youngs_modulus=5e4, density=200)], options)


def test_model_to_cloud_balance_is_reachable():
    # weights.model_to_cloud_balance (on by default) from Python: a 1053-vertex box under a cloud of
    # a tenth of its surface points (153, against ~600 surface vertices) follows a rigid
    # translation, closer with the balance on (docs/notes/2026-11-28-figures-from-code-comments.md).
    mesh = femreg.make_box([0.06, 0.04, 0.04], [12, 8, 8])
    assert femreg.RegistrationOptions().weights.model_to_cloud_balance
    shift = np.array([0.004, -0.002, 0.001])
    cloud = _surface_cloud(mesh, mesh.rest + shift)
    cloud = cloud[np.random.default_rng(1).permutation(len(cloud))[: len(cloud) // 10]]
    errors = {}
    for balance in (True, False):
        options = femreg.RegistrationOptions()
        options.solver.max_outer_iterations = 10
        options.weights.model_to_cloud_balance = balance
        tracker = femreg.Tracker([mesh], [femreg.Material(youngs_modulus=5e4, density=200)], options)
        for _ in range(4):
            x = tracker.track(cloud)
        assert tracker.summary["usable"]
        errors[balance] = np.abs(x - (mesh.rest + shift)).mean()
    assert errors[True] < 1e-3 and errors[False] < 1e-3
    assert errors[True] < errors[False]


def test_gravity_bends_what_the_camera_does_not_see():
    mesh = femreg.make_box([0.2, 0.04, 0.04], [10, 2, 2])
    options = femreg.RegistrationOptions()
    options.solver.max_outer_iterations = 20
    clamped = [int(v) for v in np.flatnonzero(mesh.rest[:, 0] < 1e-9)]
    near = mesh.rest[mesh.rest[:, 0] < 0.1]  # the camera sees the clamped half, at rest
    unseen = mesh.rest[:, 0] > 0.15
    sag = {}
    for g in (0.0, -9.81):
        tracker = femreg.Tracker([mesh], [femreg.Material(youngs_modulus=2e5, density=1000)], options)
        tracker.add_anchor("clamp", 0, clamped, hard=True)
        tracker.set_external_loads(0, [0, 0, g])
        x = tracker.track(near)
        sag[g] = float((mesh.rest[unseen, 2] - x[unseen, 2]).mean())
        assert (tracker.summary["final_energy"]["load"] != 0.0) == (g != 0.0)
    assert abs(sag[0.0]) < 1e-3
    assert sag[-9.81] > 5e-3  # the free end hangs down
    with pytest.raises(ValueError):
        tracker.set_external_loads(0, [0, 0, -9.81], vertices=[0])


def test_estimated_forces_hold_up_what_is_seen_at_rest():
    # Equilibrium registration (docs/theory/equilibrium.md): a clamped bar under gravity seen
    # whole and unbent needs external forces that carry its weight: their resultant is the
    # weight, upwards, and each vertex's force is in external_forces.
    mesh = femreg.make_box([0.2, 0.04, 0.04], [10, 2, 2])
    options = femreg.RegistrationOptions()
    options.forces.estimate = True
    options.forces.weight = 0.01
    options.solver.max_outer_iterations = 10
    clamped = [int(v) for v in np.flatnonzero(mesh.rest[:, 0] < 1e-9)]
    material = femreg.Material(youngs_modulus=2e5, density=1000)
    tracker = femreg.Tracker([mesh], [material], options)
    tracker.add_anchor("clamp", 0, clamped, hard=True)
    tracker.set_external_loads(0, [0, 0, -9.81])
    tracker.track(_surface_cloud(mesh, mesh.rest))
    summary = tracker.summary
    assert summary["usable"] and summary["final_energy"]["equilibrium"] > 0
    weight = 1000 * 0.2 * 0.04 * 0.04 * 9.81
    np.testing.assert_allclose(summary["force"], [0, 0, weight], atol=0.1 * weight)
    forces = tracker.external_forces(0)
    assert forces.shape == (mesh.num_vertices, 3)
    np.testing.assert_allclose(forces.sum(axis=0), summary["force"], atol=1e-9)
    assert np.all(forces[clamped] == 0)  # the clamp's reaction is not an external force
    # The Ceres back end solves the same problem (a reference, slower): the same force.
    options.solver.backend = "ceres"
    reference = femreg.Tracker([mesh], [material], options)
    reference.add_anchor("clamp", 0, clamped, hard=True)
    reference.set_external_loads(0, [0, 0, -9.81])
    reference.track(_surface_cloud(mesh, mesh.rest))
    np.testing.assert_allclose(reference.summary["force"], summary["force"], atol=0.01 * weight)


def test_contact_forces_carry_a_resting_block():
    # A stiff block on a table under gravity, seen from above: the table's force per frame
    # (summary["contact_forces"], docs/theory/contact.md#what-is-reported) is its weight.
    scene = femreg.parse_scene("""
objects:
  - {name: block, generate: {shape: box, size: [0.04, 0.04, 0.02], cells: [4, 4, 2]},
     material: {youngs_modulus: 1.0e8, poisson_ratio: 0.3, density: 1000}}
gravity: [0, 0, -9.81]
effects: {collision: true}
collision:
  friction: 0.5
  obstacles:
    - {name: table, plane: {point: [0, 0, 0], normal: [0, 0, 1]}}
""")
    tracker = femreg.Tracker(scene)
    g = np.linspace(0.004, 0.036, 17)
    points = np.array([[x, y, 0.02] for x in g for y in g])
    normals = np.tile([0.0, 0.0, 1.0], (len(points), 1))
    for _ in range(5):
        tracker.track(points, normals)
    forces = tracker.summary["contact_forces"]
    assert len(forces) == 1 and forces[0]["object"] == 0 and forces[0]["other"] == -1
    weight = 1000 * 0.04 * 0.04 * 0.02 * 9.81
    np.testing.assert_allclose(forces[0]["force"], [0, 0, weight], atol=0.01 * weight)
    np.testing.assert_allclose(forces[0]["friction"], [0, 0, 0], atol=0.01 * weight)


def test_tracker_reports_bad_frames_in_the_summary():
    mesh = femreg.make_box([0.1, 0.02, 0.02], [5, 1, 1])
    tracker = femreg.Tracker([mesh], [femreg.Material()])
    x = tracker.track(np.full((10, 3), np.nan))
    assert tracker.summary["termination"] in ("invalid_input", "no_correspondences")
    assert tracker.summary["nonfinite_dropped"] == 10
    np.testing.assert_array_equal(x, mesh.rest)  # the shape is held


def test_float32_and_strided_input_are_accepted():
    mesh = femreg.make_box([0.1, 0.02, 0.02], [5, 1, 1])
    cloud = _surface_cloud(mesh, mesh.rest)
    a = femreg.Tracker([mesh], [femreg.Material()])
    b = femreg.Tracker([mesh], [femreg.Material()])
    xa = a.track(cloud.astype(np.float32).astype(np.float64))
    # A float32 array and a non-contiguous view (every column of a (N, 6) array) give the
    # same cloud, hence the same result bit for bit.
    wide = np.concatenate([cloud.astype(np.float32).astype(np.float64), np.zeros_like(cloud)], axis=1)
    xb = b.track(wide[:, :3])
    np.testing.assert_array_equal(xa, xb)


def test_simulate_beam(datasets):
    scene = femreg.load_scene(str(datasets / "beam" / "beam.yaml"))
    result = femreg.simulate(scene)
    assert result["converged"], result["message"]
    x = result["vertices"]
    rest = result["mesh"].rest
    assert x.shape == rest.shape
    np.testing.assert_allclose(np.linalg.norm(x - rest, axis=1).max(), result["max_displacement"],
                               rtol=1e-12)
    with pytest.raises(ValueError, match="no such object"):
        femreg.simulate(scene, object="nope")


def test_an_embedded_surface_is_tracked_and_returned():
    # A coarse cage carries a finer box's surface: the data act on the fine surface, and
    # surface_vertices returns it.
    cage = femreg.make_box([0.202, 0.042, 0.042], [5, 1, 1], origin=[-0.001, -0.001, -0.001])
    fine = femreg.make_box([0.2, 0.04, 0.04], [20, 4, 4])
    used = np.unique(fine.surface)
    index = -np.ones(fine.num_vertices, dtype=int)
    index[used] = np.arange(len(used))
    scan, faces = fine.rest[used], index[fine.surface]
    options = femreg.RegistrationOptions()
    options.solver.max_outer_iterations = 10
    tracker = femreg.Tracker([cage], [femreg.Material(youngs_modulus=5e4, density=200)], options)
    assert tracker.surface_vertices(0).shape == (0, 3)
    tracker.set_embedded_surface(0, scan, faces)
    np.testing.assert_allclose(tracker.surface_vertices(0), scan, atol=1e-12)
    np.testing.assert_array_equal(tracker.surface_triangles(0), faces)
    shift = np.array([0.004, -0.002, 0.001])
    for _ in range(4):
        tracker.track(_surface_cloud(fine, fine.rest + shift))
    assert tracker.summary["usable"]
    # The outputs after the outer iterations (per-vertex distances, confidence) have their time.
    times = tracker.summary["time_s"]
    assert 0 < times["outputs"] < times["total"]
    # The fine surface reaches the shifted scan, although the cage is 1 mm larger than it.
    assert np.abs(tracker.surface_vertices(0) - (scan + shift)).max() < 2e-4
    with pytest.raises(femreg.Error, match="out of range"):
        tracker.set_embedded_surface(0, scan, faces + len(scan))
