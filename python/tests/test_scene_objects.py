"""A scene's objects from Python: scene.objects and scene.object(name) give each object's own
values (its table's rows) and its material to read and write in place, checked as the scene
file's are, and a tracker built from the scene afterwards uses them."""
import numpy as np
import pytest

import femreg

BAR = ("objects:\n  - name: bar\n    generate: {{shape: box, size: [0.2, 0.04, 0.04], cells: [10, 2, 2]}}\n"
       "    material: {{youngs_modulus: {E}, poisson_ratio: 0.3, density: 1000{extra}}}\n")


def bar_scene(E=1e5, extra=""):
    scene = femreg.parse_scene(BAR.format(E=E, extra=extra))
    scene.registration.solver.max_outer_iterations = 20
    return scene


def hang(scene):
    """The bar clamped at x = 0 under gravity, the camera seeing its clamped half at rest:
    the unseen end hangs as the material lets it."""
    tracker = femreg.Tracker(scene)
    rest = tracker.mesh(0).rest
    tracker.add_anchor("clamp", 0, [int(v) for v in np.flatnonzero(rest[:, 0] < 1e-9)], hard=True)
    tracker.set_external_loads(0, [0, 0, -9.81])
    return tracker.track(rest[rest[:, 0] < 0.1])


def test_objects_read_and_write_in_place():
    scene = bar_scene()
    assert [o.name for o in scene.objects] == ["bar"] and scene.object("bar").mesh == ""
    bar = scene.object("bar")
    assert bar.scale == 1.0 and bar.material_model is None and bar.label == -1
    assert list(bar.translation) == [0.0, 0.0, 0.0]
    bar.material.youngs_modulus = 2e5          # the material, in place
    bar.material_model = "neo_hookean"         # the table's rows
    bar.translation = [0.1, 0.0, 0.0]
    bar.toughness = 5e4
    assert scene.objects[0].material.youngs_modulus == 2e5 and scene.object(0).material_model == "neo_hookean"
    assert "SceneObject(name='bar', scale=1.0, translation=[0.1, 0.0, 0.0]" in repr(bar)
    again = femreg.parse_scene(scene.to_yaml())   # written back as the scene file's keys
    assert again.object("bar").material.youngs_modulus == 2e5
    assert again.object("bar").material_model == "neo_hookean"
    assert list(again.object("bar").translation) == pytest.approx([0.1, 0, 0])
    assert again.object("bar").toughness == 5e4
    bar.material_model = None                  # unset again
    assert "model" not in scene.to_yaml()
    with pytest.raises(ValueError, match="no such object"):
        scene.object("nope")


def test_a_tracker_uses_what_python_set():
    # Material and model set from Python hang the bar exactly as the same values in the file.
    scene = bar_scene(E=1e5)
    scene.object("bar").material.youngs_modulus = 2e5
    scene.object("bar").material_model = "neo_hookean"
    x_python = hang(scene)
    x_file = hang(bar_scene(E=2e5, extra=", model: neo_hookean"))
    np.testing.assert_allclose(x_python, x_file, rtol=0, atol=1e-12)
    # ... and not as the file's own values: the softer bar hangs lower.
    x_before = hang(bar_scene(E=1e5))
    end = x_file[:, 0] > 0.15
    assert x_before[end, 2].mean() < x_file[end, 2].mean() - 1e-3
    assert np.abs(hang(bar_scene(E=2e5)) - x_file).max() > 1e-9   # hooke: another element
    # The pose set from Python moves the tracker's rest shape.
    scene.object("bar").translation = [0.1, 0.0, 0.0]
    assert femreg.Tracker(scene).mesh(0).rest[:, 0].min() == pytest.approx(0.1)


def test_bad_values_raise_value_error_naming_the_field():
    scene = bar_scene()
    bar = scene.object("bar")
    with pytest.raises(ValueError, match=r"^objects.scale must be > 0 \(got -1"):
        bar.scale = -1
    assert bar.scale == 1.0                      # left as it was
    with pytest.raises(ValueError, match=r"objects.toughness must be >= 0"):
        bar.toughness = -5.0
    with pytest.raises(ValueError, match=r"objects.label must be >= -1"):
        bar.label = -2
    with pytest.raises(ValueError, match=r"objects.material.model: unknown value 'rubber' \(use hooke, neo_hookean\)"):
        bar.material_model = "rubber"
    with pytest.raises(TypeError, match="objects.pose.translation: cannot take"):
        bar.translation = "up"
    # Nodal volume needs the neo-Hookean element: the scene parser's message, for the field set,
    # with the object's name.
    with pytest.raises(ValueError, match=r"^objects.material.volume \(object 'bar'\): 'nodal' needs "
                                         r"'model: neo_hookean'") as info:
        bar.material_volume = "nodal"
    assert bar.material_volume is None
    with pytest.raises(femreg.Error) as parsed:
        bar_scene(extra=", volume: nodal")
    assert str(info.value).split(": ", 1)[1] in str(parsed.value)
    bar.material_model = "neo_hookean"
    bar.material_volume = "nodal"
    # Here the model set is the row that breaks the rule: the message names it.
    with pytest.raises(ValueError, match=r"^objects.material.model \(object 'bar'\): 'nodal' needs"):
        bar.material_model = "hooke"
    assert bar.material_model == "neo_hookean"
    with pytest.raises(femreg.Error, match=r"objects\[0\].material.model: 'nodal' needs"):
        bar_scene(extra=", volume: nodal, model: hooke")
    bar.material = femreg.Material(youngs_modulus=3e5)
    assert scene.object(0).material.youngs_modulus == 3e5


def test_a_material_changed_in_place_is_checked_when_set():
    scene = bar_scene()
    bar = scene.object("bar")
    # Through the object, in place: raised at the assignment, naming the key, the value kept.
    with pytest.raises(ValueError, match=r"^Material: youngs_modulus must be > 0 \(got -1"):
        bar.material.youngs_modulus = -1
    assert bar.material.youngs_modulus == 1e5
    with pytest.raises(ValueError, match=r"^Material: poisson_ratio must be in \(-1, 0.5\) \(got 0.7"):
        scene.objects[0].material.poisson_ratio = 0.7
    with pytest.raises(ValueError, match=r"^Material: density must be > 0"):
        scene.object(0).material.density = 0
    assert scene.object(0).material.poisson_ratio == 0.3 and scene.object(0).material.density == 1000
    with pytest.raises(TypeError, match="youngs_modulus: cannot take"):
        bar.material.youngs_modulus = "stiff"
    bar.material.youngs_modulus = 2e5                   # a good value is taken
    assert scene.object("bar").material.youngs_modulus == 2e5
    # A Material of its own, as its constructor does.
    soft = femreg.Material()
    with pytest.raises(ValueError, match=r"^Material: poisson_ratio must be in \(-1, 0.5\)"):
        soft.poisson_ratio = 0.5
    assert soft.poisson_ratio == 0.3
