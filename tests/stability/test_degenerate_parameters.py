"""Degenerate parameters fail loudly: NaN or Inf coordinates, up parallel to the view, eye equal to
center, fovy outside (0, 180), near <= 0, a zero-sized image, and bad light and material values
raise SceneError naming the field, from a scene file and from a scene built in Python, before any
kernel runs (the test makes any Warp launch or BVH build fail)."""

import copy
import math
from dataclasses import replace

import numpy as np
import pytest
import warp as wp

import warprt
from scenekit import write_scene
from warprt import Camera, SceneError
from warprt.scene import load_scene, scene_from_dict

GOOD = {
    "camera": {"eye": [0.0, 1.0, 5.0], "center": [0.0, 0.0, 0.0], "up": [0.0, 1.0, 0.0], "fovy": 45.0, "near": 1.0,
               "width": 32, "height": 24},
    "render": {"max_depth": 3},
    "lights": [{"position": [2.0, 4.0, 3.0], "color": [1.0, 1.0, 1.0]}],
    "materials": {"m": {"kd": [0.5, 0.5, 0.5], "reflectivity": 0.5}},
    "objects": [{"shape": "sphere", "material": "m"}],
}
NAN, INF = math.nan, math.inf

# (case, dotted key to set, value, field named in the error)
CASES = [
    ("eye NaN", "camera.eye", [NAN, 0.0, 5.0], "camera.eye"),
    ("eye Inf", "camera.eye", [0.0, INF, 5.0], "camera.eye"),
    ("center -Inf", "camera.center", [0.0, -INF, 0.0], "camera.center"),
    ("up NaN", "camera.up", [0.0, NAN, 0.0], "camera.up"),
    ("up parallel to view", "camera.up", [0.0, 1.0, 5.0], "camera.up"),
    ("up anti-parallel", "camera.up", [0.0, -2.0, -10.0], "camera.up"),
    ("up zero", "camera.up", [0.0, 0.0, 0.0], "camera.up"),
    ("eye equals center", "camera.center", [0.0, 1.0, 5.0], "camera.center"),
    ("fovy 0", "camera.fovy", 0.0, "camera.fovy"),
    ("fovy 180", "camera.fovy", 180.0, "camera.fovy"),
    ("fovy negative", "camera.fovy", -30.0, "camera.fovy"),
    ("fovy 270", "camera.fovy", 270.0, "camera.fovy"),
    ("fovy NaN", "camera.fovy", NAN, "camera.fovy"),
    ("near 0", "camera.near", 0.0, "camera.near"),
    ("near negative", "camera.near", -1.0, "camera.near"),
    ("near Inf", "camera.near", INF, "camera.near"),
    ("near below float32", "camera.near", 1e-40, "camera.near"),
    ("width 0", "camera.width", 0, "camera.width"),
    ("height 0", "camera.height", 0, "camera.height"),
    ("light position NaN", "lights[0].position", [NAN, 1.0, 1.0], "lights[0].position"),
    ("light colour Inf", "lights[0].color", [INF, 1.0, 1.0], "lights[0].color"),
    ("light colour negative", "lights[0].color", [-1.0, 1.0, 1.0], "lights[0].color"),
    ("light beyond float32 reach", "lights[0].position", [1e20, 0.0, 0.0], "lights[0].position"),
    ("kd NaN", "materials.m.kd", [NAN, 0.5, 0.5], "materials.m.kd"),
    ("ks negative", "materials.m.ks", [0.5, -0.1, 0.5], "materials.m.ks"),
    ("shininess Inf", "materials.m.shininess", INF, "materials.m.shininess"),
    ("reflectivity NaN", "materials.m.reflectivity", NAN, "materials.m.reflectivity"),
    ("reflectivity 3 over 1024 levels", "materials.m.reflectivity", 3.0, "render.max_depth"),
    ("ambient NaN", "render.ambient", [NAN, 0.1, 0.1], "render.ambient"),
    ("translate Inf", "objects[0].translate", [INF, 0.0, 0.0], "objects[0].translate"),
    ("scale NaN", "objects[0].scale", NAN, "objects[0].scale"),
    ("object beyond float32 reach", "objects[0].translate", [0.0, 0.0, -1e19], "objects[0]"),
]


def with_value(key, value):
    doc = copy.deepcopy(GOOD)
    if key == "materials.m.reflectivity" and value == 3.0:
        doc["render"]["max_depth"] = 1024
    node, parts = doc, key.replace("[0]", ".0").split(".")
    for part in parts[:-1]:
        node = node[int(part)] if part.isdigit() else node[part]
    node[parts[-1]] = value
    return doc


@pytest.fixture
def no_kernels(monkeypatch):
    """Any Warp launch or BVH build during the test fails it."""
    def refuse(*args, **kwargs):
        raise AssertionError("a kernel or BVH build ran before the bad input was reported")
    monkeypatch.setattr(wp, "launch", refuse)
    monkeypatch.setattr(wp, "Mesh", refuse)  # the BVH


def test_the_good_scene_is_good():
    scene = scene_from_dict(copy.deepcopy(GOOD), "<good>")
    image, _ = warprt.render(scene)
    assert np.isfinite(image).all() and image.max() > 0


@pytest.mark.parametrize("case,key,value,field", CASES, ids=[c[0] for c in CASES])
def test_scene_file_names_the_field(tmp_path, no_kernels, case, key, value, field):
    """Through a real TOML file (tomllib reads nan and inf), as the CLI does."""
    path = write_scene(tmp_path, with_value(key, value), "bad.toml")
    with pytest.raises(SceneError) as e:
        load_scene(path)
    assert e.value.field == field and str(e.value).startswith(f"{path}: {field}: ")


@pytest.mark.parametrize("case,key,value,field", [c for c in CASES if c[1].split(".")[0] in ("camera", "lights", "materials")],
                         ids=[c[0] for c in CASES if c[1].split(".")[0] in ("camera", "lights", "materials")])
def test_python_api_names_the_field_before_any_kernel(no_kernels, case, key, value, field):
    """A user who builds Camera / Light / Material in Python and calls render() gets the same error."""
    scene = scene_from_dict(copy.deepcopy(GOOD), "<api>")
    section, rest = key.split(".", 1)
    if section == "camera":
        scene = replace(scene, camera=replace(scene.camera, **{rest: tuple(value) if isinstance(value, list) else value}))
    elif section == "lights":
        scene.lights = [replace(scene.lights[0], **{rest.split(".")[1]: tuple(value)})]
    else:
        name = rest.split(".")[1]
        v = tuple(value) if isinstance(value, list) else (value if name == "shininess" else (value,) * 3)
        scene.materials = {**scene.materials, "m": replace(scene.materials["m"], **{name: v})}
        if value == 3.0:
            scene = scene.with_render(max_depth=1024)
    with pytest.raises(SceneError) as e:
        warprt.render(scene)
    assert e.value.field == field, str(e.value)


def test_python_api_checks_objects_and_render_settings(no_kernels):
    scene = scene_from_dict(copy.deepcopy(GOOD), "<api>")
    obj = scene.objects[0]
    bad_vertices = obj.vertices.copy()
    bad_vertices[3, 1] = NAN
    for change, field in [(lambda s: setattr(s.objects[0], "vertices", bad_vertices), "objects[0].vertices"),
                          (lambda s: setattr(s.objects[0], "faces", obj.faces + 10_000), "objects[0].faces"),
                          (lambda s: setattr(s.objects[0], "material", "nope"), "objects[0].material")]:
        s = scene_from_dict(copy.deepcopy(GOOD), "<api>")
        change(s)
        with pytest.raises(SceneError) as e:
            warprt.render(s)
        assert e.value.field == field
    for kw, field in [({"max_depth": 0}, "render.max_depth"), ({"spp": 3}, "render.spp"),
                      ({"background": (0.0, INF, 0.0)}, "render.background")]:
        with pytest.raises(SceneError) as e:
            warprt.render(scene.with_render(**kw))
        assert e.value.field == field
    cam = Camera(eye=(0.0, 0.0, 0.0), center=(0.0, 0.0, 0.0))
    with pytest.raises(SceneError) as e:
        warprt.render(replace(scene, camera=cam))
    assert e.value.field == "camera.center"
