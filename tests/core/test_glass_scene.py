"""Dielectric materials as the scene reads and checks them: ior, transmittance and absorption from the
file and from Python, the closed-mesh check (and its warning), and which glass holds the eye."""

import warnings
from dataclasses import replace

import numpy as np
import pytest

import warprt
from scenekit import make_scene
from warprt.scene import Material, eye_medium, open_edges, shapes, signed_volume, validate_scene, winding_number

BOX = {"shape": "box", "size": 1.0, "material": "glass"}


def test_glass_keys_are_read_with_their_defaults():
    scene = make_scene([BOX], {"glass": {"ior": 1.33, "transmittance": 0.8, "absorption": [0.1, 0.2, 0.3]},
                               "clear": {"ior": 1.5}, "paint": {"kd": [0.5] * 3}})
    glass, clear, paint = (scene.materials[n] for n in ("glass", "clear", "paint"))
    assert (glass.ior, glass.transmittance, glass.absorption) == (1.33, (0.8, 0.8, 0.8), (0.1, 0.2, 0.3))
    assert (clear.ior, clear.transmittance, clear.absorption) == (1.5, (1.0, 1.0, 1.0), (0.0, 0.0, 0.0))
    assert paint.ior is None and not paint.dielectric and clear.dielectric


@pytest.mark.parametrize("material, field, message", [
    (Material(ior=-1.0), "ior", "expected a finite number > 0, got -1"),
    (Material(ior=float("nan")), "ior", "expected a finite number > 0, got nan"),
    (Material(ior=1.5, reflectivity=(0.5, 0.5, 0.5)), "reflectivity", "reflects by its Fresnel term"),
    (Material(ior=1.5, transmittance=(1.2, 1.0, 1.0)), "transmittance", "expected values in [0, 1]"),
    (Material(ior=1.5, absorption=(-0.1, 0.0, 0.0)), "absorption", "expected 3 finite non-negative numbers"),
    (Material(transmittance=(0.5, 0.5, 0.5)), "transmittance", "only a dielectric has it"),
    (Material(absorption=(0.0, 0.1, 0.0)), "absorption", "only a dielectric has it"),
])
def test_a_scene_built_in_python_gets_the_files_checks(material, field, message):
    scene = make_scene([BOX], {"glass": {"ior": 1.5}})
    bad = replace(scene, materials={**scene.materials, "glass": material})
    with pytest.raises(warprt.SceneError) as e:
        validate_scene(bad)
    assert e.value.field == f"materials.glass.{field}" and message in e.value.message


def test_built_in_shapes_are_closed_and_outward_except_the_plane():
    for name, (build, _) in shapes.SHAPES.items():
        if name in ("triangles", "torus_knot"):
            continue
        v, f = build()
        if name == "plane":
            assert open_edges(v, f) == 4  # its border
        else:
            assert open_edges(v, f) == 0 and signed_volume(v, f) > 0, name


def test_open_edges_counts_holes_and_inconsistent_winding():
    v, f = shapes.box(1.0)
    assert open_edges(v, f[1:]) == 3  # one triangle fewer: its three edges border one face each
    flipped = f.copy()
    flipped[0] = flipped[0, ::-1]
    assert open_edges(v, flipped) == 3  # its three edges are now run the same way by both faces
    # Duplicated vertices at the same place are one vertex: a box made of separate faces is closed.
    split = v[f].reshape(-1, 3)
    assert open_edges(split, np.arange(len(split)).reshape(-1, 3)) == 0
    assert signed_volume(v, f[:, ::-1]) == pytest.approx(-1.0)


def _warnings(objects, materials):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        make_scene(objects, materials)
    return [str(w.message) for w in caught if issubclass(w.category, warprt.SceneWarning)]


def test_an_open_or_inward_glass_mesh_is_warned_about_once():
    glass = {"glass": {"ior": 1.5}, "paint": {"kd": [0.5] * 3}}
    assert _warnings([BOX], glass) == []
    assert _warnings([{"shape": "plane", "material": "paint"}], glass) == []  # opaque: may be open
    (message,) = _warnings([{"shape": "plane", "material": "glass"}], glass)
    assert message == ("<test>: objects[0]: 'plane' has ior but is not closed (4 open or inconsistently wound "
                       "edges): rays leaving through them stay inside")
    inward = {"shape": "triangles", "vertices": shapes.box(1.0)[0].tolist(), "faces": shapes.box(1.0)[1][:, ::-1].tolist(),
              "material": "glass"}
    (message,) = _warnings([inward], glass)
    assert "is wound inward (negative volume)" in message


def test_the_winding_number_says_inside_and_outside():
    v, f = shapes.sphere(1.0, 2)
    assert winding_number(v, f, [0.1, 0.2, -0.3]) == pytest.approx(1.0)
    assert winding_number(v, f, [2.0, 0.0, 0.0]) == pytest.approx(0.0, abs=1e-12)
    assert winding_number(v, f[:, ::-1], [0.0, 0.0, 0.0]) == pytest.approx(-1.0)


def test_the_eye_medium_is_the_glass_that_holds_the_eye():
    objects = [{**BOX, "size": 4.0, "material": "water"}, {**BOX, "translate": [0.0, 0.0, -5.0]}]
    materials = {"water": {"ior": 1.33}, "glass": {"ior": 1.5}}
    assert eye_medium(make_scene(objects, materials, camera={"eye": [0.0, 0.0, 1.0]})) == "water"
    assert eye_medium(make_scene(objects, materials, camera={"eye": [0.0, 0.0, 5.0]})) is None
    nested = make_scene([objects[0], {**BOX, "material": "glass"}], materials, camera={"eye": [0.0, 0.0, 0.1]})
    with pytest.raises(warprt.SceneError, match="camera.eye: is inside more than one object with ior"):
        eye_medium(nested)
