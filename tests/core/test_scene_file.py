"""The scene file: the documented example parses to the documented values and defaults; rotate and
smooth normals are the README's, as the oracle derives them."""


import numpy as np
import pytest
import trimesh

import warprt
from oracle import rotation, vertex_normals
from scenekit import write_scene

EXAMPLE = {
    "camera": {"eye": [0.0, 1.5, 5.0], "center": [0.0, 0.8, 0.0], "up": [0.0, 1.0, 0.0], "fovy": 45.0, "near": 1.0,
               "width": 64, "height": 48},
    "render": {"ambient": [0.1, 0.1, 0.1], "background": [0.0, 0.0, 0.0], "max_depth": 3, "shadows": True, "spp": 1},
    "lights": [{"position": [4.0, 6.0, 4.0], "color": [1.0, 1.0, 1.0]}],
    "materials": {
        "red": {"ka": [0.2, 0.02, 0.02], "kd": [0.7, 0.1, 0.1], "ks": [0.5, 0.5, 0.5], "shininess": 32.0, "reflectivity": 0.0},
        "plain": {"kd": [0.3, 0.4, 0.5], "reflectivity": 0.25},
    },
    "objects": [
        {"mesh": "meshes/thing.ply", "material": "red", "scale": 2.0, "rotate": [0.0, 90.0, 0.0],
         "translate": [1.0, 0.0, 0.0], "smooth": False},
        {"shape": "box", "size": [1.0, 2.0, 3.0], "material": "plain"},
    ],
}


def test_example_scene_parses(tmp_path):
    (tmp_path / "meshes").mkdir()
    tri = trimesh.Trimesh(vertices=[[0, 0, 0], [1, 0, 0], [0, 1, 0]], faces=[[0, 1, 2]], process=False)
    tri.export(tmp_path / "meshes" / "thing.ply")
    scene = warprt.load_scene(write_scene(tmp_path, EXAMPLE))
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


def test_rotate_is_rz_ry_rx_of_the_readme():
    """Any angles: each vertex becomes R p with R = Rz Ry Rx (tests/oracle/transform.py, from
    Rodrigues' formula), then the translation is added."""
    rng = np.random.default_rng(7)
    points = rng.normal(size=(3, 3))
    for degrees in rng.uniform(-360, 360, (6, 3)):
        scene = warprt.scene.scene_from_dict({"objects": [{"shape": "triangles", "vertices": points.tolist(), "faces": [[0, 1, 2]],
                                                             "rotate": degrees.tolist(), "translate": [1.0, -2.0, 0.5]}]})
        np.testing.assert_allclose(scene.objects[0].vertices, points @ rotation(degrees).T + [1.0, -2.0, 0.5], atol=1e-12)


def split_sphere():
    """An icosphere whose eastern faces index a copy of its vertices: a seam along x = 0 that only
    sharing normals by position closes."""
    obj = warprt.scene.scene_from_dict({"objects": [{"shape": "sphere", "subdivisions": 2}]}).objects[0]
    east = obj.vertices[obj.faces].mean(axis=1)[:, 0] > 0
    faces = np.where(east[:, None], obj.faces + len(obj.vertices), obj.faces)
    return {"shape": "triangles", "vertices": np.concatenate([obj.vertices, obj.vertices]).tolist(), "faces": faces.tolist()}


@pytest.mark.parametrize("shape", [{"shape": "sphere", "subdivisions": 2, "scale": [1.0, 0.6, 1.3]},
                                   {"shape": "box", "size": [1.0, 2.0, 3.0], "rotate": [10.0, 20.0, 30.0]},
                                   split_sphere()], ids=["squashed sphere", "box", "sphere split at a seam"])
def test_smooth_normals_are_angle_weighted(shape):
    """The smooth normals the renderer and the Mitsuba reference shade with (warprt.scene.vertex_normals)
    are the oracle's angle-weighted ones, shared across seams."""
    obj = warprt.scene.scene_from_dict({"objects": [{**shape, "smooth": True}]}).objects[0]
    np.testing.assert_allclose(warprt.scene.vertex_normals(obj.vertices, obj.faces), vertex_normals(obj.vertices, obj.faces),
                               atol=1e-12)
