"""A frame's scene made from the loaded one (warprt.scene.with_overrides, what every worker does) is
warprt.load_scene(path, overrides): the same fields, the same image to the bit, the same errors."""

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

import warprt
from warprt.dataset import FrameScenes
from warprt.scene import MAX_REACH, validate_scene, validate_view, with_overrides

from dataset.jobs import SCENE

BASE = {"camera.width": 24, "camera.height": 18}


def same_scene(a, b):
    assert (a.camera, a.render, a.lights, a.materials, a.source) == (b.camera, b.render, b.lights, b.materials, b.source)
    assert [(o.name, o.material, o.smooth) for o in a.objects] == [(o.name, o.material, o.smooth) for o in b.objects]
    for x, y in zip(a.objects, b.objects):
        assert np.array_equal(x.vertices, y.vertices) and np.array_equal(x.faces, y.faces)


IN_PLACE = [
    {"camera.eye": [1.0, 2.0, 4.0], "camera.fovy": 30},  # an int where the file has a float
    {"camera.center": [0.2, 0.5, 0.0], "camera.up": [0.1, 1.0, 0.0], "camera.near": 0.5},
    {"render.spp": 4, "render.max_depth": 1},
    {"render.shadows": False, "render.effects": ["ambient", "diffuse"], "render.background": [0.1, 0.2, 0.3]},
    {"camera.width": 20},  # a base field changed
]


@pytest.mark.parametrize("extra", IN_PLACE, ids=[",".join(e) for e in IN_PLACE])
def test_camera_and_render_fields_are_set_in_place_as_the_file_would_have_them(extra):
    base = warprt.load_scene(SCENE, BASE)
    overrides = {**BASE, **extra}
    frame = with_overrides(base, SCENE, overrides, BASE)
    expected = warprt.load_scene(SCENE, overrides)
    same_scene(frame, expected)
    assert frame.objects is base.objects  # not read again: the geometry cache keeps them
    assert np.array_equal(warprt.render(frame).image, warprt.render(expected).image)


@pytest.mark.parametrize("overrides", [
    {**BASE, "lights[0].color": [0.5, 0.4, 0.3]},
    {**BASE, "materials.floor.kd": [0.1, 0.2, 0.3]},
    {"camera.width": 24},  # camera.height dropped: the file's value comes back
])
def test_other_fields_load_the_file_again(overrides):
    base = warprt.load_scene(SCENE, BASE)
    frame = with_overrides(base, SCENE, overrides, BASE)
    same_scene(frame, warprt.load_scene(SCENE, overrides))
    assert frame.objects is not base.objects


@pytest.mark.parametrize("bad", [
    {"camera.fovy": -30}, {"camera.fvoy": 30}, {"render.spp": 3}, {"camera.eye": [0.0, 0.6, 0.0]},
    {"camera.eye": [0.0, 1.0]}, {"render.shadows": 1}, {"render.ambient[0]": 0.5}, {"lights[9].color": [1, 1, 1]},
])
def test_bad_values_give_load_scenes_error(bad):
    """render.ambient[0]: the file has no ambient to index (the loaded scene's default would have one)."""
    base = warprt.load_scene(SCENE, BASE)
    with pytest.raises(warprt.SceneError) as expected:
        warprt.load_scene(SCENE, {**BASE, **bad})
    with pytest.raises(warprt.SceneError) as got:
        with_overrides(base, SCENE, {**BASE, **bad}, BASE)
    assert (got.value.source, got.value.field, got.value.message) == \
           (expected.value.source, expected.value.field, expected.value.message)


def test_a_mesh_file_scene_too(tmp_path):
    mesh = tmp_path / "tri.obj"
    mesh.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    base = warprt.load_scene(mesh, {"camera.width": 16})
    overrides = {"camera.width": 16, "camera.fovy": 20.0, "render.spp": 4}
    same_scene(with_overrides(base, mesh, overrides, {"camera.width": 16}), warprt.load_scene(mesh, overrides))


def test_frame_scenes_share_objects_between_frames_that_differ_in_the_camera_only():
    scenes = FrameScenes(SCENE)
    a = scenes.scene({**BASE, "camera.eye": [1.0, 1.5, 5.0]})
    b = scenes.scene({**BASE, "camera.eye": [-1.0, 1.5, 5.0], "render.spp": 4})
    c = scenes.scene({**BASE, "lights[1].color": [1.0, 0.0, 0.0]})
    assert a.objects is b.objects and c.objects is not a.objects
    same_scene(c, warprt.load_scene(SCENE, {**BASE, "lights[1].color": [1.0, 0.0, 0.0]}))
    assert scenes.scene({**BASE, "camera.fovy": 20.0}).objects is a.objects  # the first kept meanwhile


# --- a frame's checks against the loaded scene's (validate_view) ----------------------------------------

REPO_SCENES = Path(__file__).resolve().parents[2] / "scenes"
CHECKED = ["seed", "sun", "spot_lit", "vertex_colors", "glass_slab", "whitted", "falloff"]


def outcome(check, scene):
    """None, or the SceneError's field and message."""
    try:
        check(scene)
    except warprt.SceneError as e:
        return e.field, e.message
    return None


def views(scene):
    """Cameras and render settings a frame may bring, good and bad, set on the scene as they are (not through
    the reader, so that bad values reach the checks): eyes at, just inside and just past the float32 reach of
    the farthest vertex along each axis and of a light, camera fields out of range, settings that overflow."""
    cam, r = scene.camera, scene.render
    lo = np.min([np.min(o.vertices, axis=0) for o in scene.objects], axis=0).astype(np.float64)
    hi = np.max([np.max(o.vertices, axis=0) for o in scene.objects], axis=0).astype(np.float64)
    out = [{}, {"eye": (3.0, 2.0, 5.0)}, {"eye": (0.5, 40.0, -7.0), "up": (1.0, 0.0, 0.0)}]
    for axis in range(3):
        for side, edge in ((1.0, lo[axis]), (-1.0, hi[axis])):
            for nudge in (-1, 0, 1):  # ulps about the bound, from the box's far side
                eye = np.array(cam.center, np.float64)
                eye[axis] = np.nextafter(edge + side * MAX_REACH, side * np.inf) if nudge > 0 else \
                    np.nextafter(edge + side * MAX_REACH, -side * np.inf) if nudge < 0 else edge + side * MAX_REACH
                out.append({"eye": tuple(eye), "center": tuple(eye - 1e3 * np.eye(3)[(axis + 1) % 3]),
                            "up": tuple(np.eye(3)[(axis + 2) % 3])})
    for light in scene.lights:
        if light.position is not None:
            out.append({"eye": tuple(np.asarray(light.position) + (MAX_REACH * 1.0000001, 0.0, 0.0))})
    out += [{"fovy": 0.0}, {"fovy": 179.9, "near": 1e-30}, {"width": 0}, {"center": cam.eye},
            {"up": tuple(np.subtract(cam.eye, cam.center))}, {"render": {"spp": 3}}, {"render": {"max_depth": 0}},
            {"render": {"ambient": (1e38, 1e38, 1e38)}}, {"render": {"background": (3e37, 0.0, 0.0)}},
            {"render": {"max_depth": 1024, "ambient": (1e30, 0.0, 0.0)}}, {"render": {"ambient": (-1.0, 0.0, 0.0)}}]
    return [replace(scene, camera=replace(cam, **{k: v for k, v in view.items() if k != "render"}),
                    render=replace(r, **view.get("render", {}))) for view in out]


@pytest.mark.parametrize("name", CHECKED)
def test_a_frames_checks_give_the_whole_scenes_verdict(name):
    """validate_view(frame, validate_scene(base)) against validate_scene(frame), for frames that change the
    camera and render settings only: the same pass, or the same first SceneError, on every view. Each scene
    has views that fail on an object's reach (at its bounding box's side, an ulp either way), a light's reach,
    the camera, the settings and float32 overflow."""
    base = warprt.load_scene(REPO_SCENES / f"{name}.toml")
    content = validate_scene(base)
    results = [(outcome(validate_scene, f), outcome(lambda s: validate_view(s, content), f)) for f in views(base)]
    assert all(a == b for a, b in results), [(i, a, b) for i, (a, b) in enumerate(results) if a != b]
    assert sum(a is None for a, _ in results) >= 3 and sum(a is not None for a, _ in results) >= 10
    assert any(a and a[0].startswith("objects[") for a, _ in results)  # the reach of the geometry was met


def test_the_comparison_sees_a_forgotten_check():
    """The negative control: a view check that forgot the objects' reach (content without objects) passes
    frames the whole scene's check refuses, and the comparison above says so. glass_slab has no lights, so
    its objects are all that bound the eye."""
    base = warprt.load_scene(REPO_SCENES / "glass_slab.toml")
    forgetful = replace(validate_scene(base), objects=())
    differ = [f for f in views(base)
              if outcome(validate_scene, f) != outcome(lambda s: validate_view(s, forgetful), f)]
    assert len(differ) >= 3


@pytest.mark.parametrize("bad", [{"camera.eye": [2e12, 1.0, 4.0]}, {"camera.fovy": -30}, {"render.spp": 3},
                                 {"render.ambient": [1e38, 1e38, 1e38]}])
def test_frame_scenes_give_load_scenes_error_from_the_checked_content(bad):
    scenes = FrameScenes(SCENE)
    scenes.scene(BASE)  # loaded and its content checked once
    with pytest.raises(warprt.SceneError) as expected:
        warprt.load_scene(SCENE, {**BASE, **bad})
    with pytest.raises(warprt.SceneError) as got:
        scenes.scene({**BASE, **bad})
    assert (got.value.source, got.value.field, got.value.message) == \
           (expected.value.source, expected.value.field, expected.value.message)
