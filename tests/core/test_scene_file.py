"""The scene file: the documented example parses to the documented values and defaults."""


import numpy as np
import pytest
import trimesh

import warprt

EXAMPLE = """
[camera]
eye = [0.0, 1.5, 5.0]
center = [0.0, 0.8, 0.0]
up = [0.0, 1.0, 0.0]
fovy = 45.0
near = 1.0
width = 64
height = 48

[render]
ambient = [0.1, 0.1, 0.1]
background = [0.0, 0.0, 0.0]
max_depth = 3
shadows = true
spp = 1

[[lights]]
position = [4.0, 6.0, 4.0]
color = [1.0, 1.0, 1.0]

[materials.red]
ka = [0.2, 0.02, 0.02]
kd = [0.7, 0.1, 0.1]
ks = [0.5, 0.5, 0.5]
shininess = 32.0
reflectivity = 0.0

[materials.plain]
kd = [0.3, 0.4, 0.5]
reflectivity = 0.25

[[objects]]
mesh = "meshes/thing.ply"
material = "red"
scale = 2.0
rotate = [0.0, 90.0, 0.0]
translate = [1.0, 0.0, 0.0]
smooth = false

[[objects]]
shape = "box"
size = [1.0, 2.0, 3.0]
material = "plain"
"""


def test_example_scene_parses(tmp_path):
    (tmp_path / "meshes").mkdir()
    tri = trimesh.Trimesh(vertices=[[0, 0, 0], [1, 0, 0], [0, 1, 0]], faces=[[0, 1, 2]], process=False)
    tri.export(tmp_path / "meshes" / "thing.ply")
    (tmp_path / "scene.toml").write_text(EXAMPLE)
    scene = warprt.load_scene(tmp_path / "scene.toml")
    assert scene.camera.fovy == 45.0 and scene.camera.width == 64
    assert scene.render.max_depth == 3 and scene.render.shadows is True
    assert scene.lights[0].position == (4.0, 6.0, 4.0)
    assert scene.materials["red"].ka == (0.2, 0.02, 0.02)
    plain = scene.materials["plain"]
    assert plain.ka == plain.kd == (0.3, 0.4, 0.5)  # ka defaults to kd
    assert plain.ks == (0.0, 0.0, 0.0) and plain.reflectivity == (0.25, 0.25, 0.25)  # scalar k_r -> RGB
    # scale 2, then 90 degrees about y (x -> -z), then translate by +1 in x.
    np.testing.assert_allclose(scene.objects[0].vertices, [[1, 0, 0], [1, 0, -2], [1, 2, 0]], atol=1e-12)
    assert scene.objects[0].vertices.dtype == np.float64
    lo, hi = scene.objects[1].vertices.min(0), scene.objects[1].vertices.max(0)
    np.testing.assert_allclose(hi - lo, [1.0, 2.0, 3.0])


@pytest.mark.parametrize("rotate,point,expect", [
    ([90, 0, 0], [0, 1, 0], [0, 0, 1]),   # about x: y -> z
    ([0, 90, 0], [0, 0, 1], [1, 0, 0]),   # about y: z -> x
    ([0, 0, 90], [1, 0, 0], [0, 1, 0]),   # about z: x -> y
    ([90, 90, 0], [0, 1, 0], [1, 0, 0]),  # x first (y -> z), then y (z -> x)
])
def test_rotation_order(rotate, point, expect):
    scene = warprt.scene.scene_from_dict({"objects": [{"shape": "triangles", "vertices": [point, [0, 0, 0], [0, 0, 0]],
                                                         "faces": [[0, 1, 2]], "rotate": rotate}]})
    np.testing.assert_allclose(scene.objects[0].vertices[0], expect, atol=1e-12)
