"""A frame's scene made from the loaded one (warprt.scene.with_overrides, what every worker does) is
warprt.load_scene(path, overrides): the same fields, the same image to the bit, the same errors."""

import numpy as np
import pytest

import warprt
from warprt.dataset import FrameScenes
from warprt.scene import with_overrides

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
