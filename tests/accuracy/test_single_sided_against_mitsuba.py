"""Single-sided glTF materials against the Mitsuba reference, which continues its rays past the same
back faces with Mitsuba's own intersection and spawn_ray: lit, seen from behind by camera, reflection
and refraction rays, every pixel as the accuracy suite checks it."""

import pytest

import warprt

from accuracy.harness import check
from formats.gltf_files import quaternion
from formats.test_single_sided import MIRROR_PLANE, SIDE_BACKDROP, quad_doc, quad_gltf
from scenekit import write_scene

pytestmark = pytest.mark.accuracy

BACKDROP = {"kd": [0.2, 0.4, 0.7], "ks": [0.3, 0.3, 0.3], "shininess": 20.0}

MIRROR = {"mirror": {"kd": [0.05, 0.05, 0.05], "reflectivity": 0.9}}

GLASS = {"glass": {"kd": [0.0, 0.0, 0.0], "ior": 1.5}}
GLASS_BOX = {"shape": "box", "size": [1.2, 1.2, 0.6], "translate": [0.3, 0.2, -1.2], "material": "glass"}


def scene(tmp_path, eye, light, backdrop, materials=None, objects=(), **quad):
    quad_gltf(tmp_path / "q.gltf", **quad)
    doc = quad_doc(eye, backdrop, BACKDROP, size=96, lights=[{"position": light, "color": [0.8, 0.8, 0.8]}],
                   ambient=[0.1, 0.1, 0.1], max_depth=3)
    doc["materials"].update(materials or {})
    doc["objects"] += [dict(o) for o in objects]
    return warprt.load_scene(write_scene(tmp_path, doc, "s.toml"))


@pytest.mark.parametrize("double_sided", [False, True])
@pytest.mark.parametrize("side", ["front", "behind"])
def test_single_sided_quad_matches_mitsuba(tmp_path, side, double_sided):
    if side == "front":
        s = scene(tmp_path, [0.5, 0.5, 4.0], [1.0, 2.0, 5.0], -2.0, double_sided=double_sided)
    else:
        s = scene(tmp_path, [0.5, 0.5, -4.0], [1.0, 2.0, -5.0], 2.0, double_sided=double_sided)
    check(f"single_sided_{side}_{'double' if double_sided else 'single'}", s)


def test_mirror_sees_through_the_back_of_a_single_sided_quad_as_mitsuba_does(tmp_path):
    s = scene(tmp_path, [0.0, 0.3, 4.0], [2.0, 3.0, 3.0], -20.0, MIRROR, [MIRROR_PLANE, SIDE_BACKDROP],
              rotation=quaternion([0.0, 1.0, 0.0], 90.0), translation=[3.0, 0.0, 0.0])
    check("single_sided_mirror", s)


def test_refracted_rays_pass_the_back_of_a_single_sided_quad_as_in_mitsuba(tmp_path):
    """The glass block stands between the camera (behind the quad) and the quad: its refracted rays meet
    the quad's back (the ray tree of reference/ray_tree.py)."""
    s = scene(tmp_path, [0.5, 0.5, -4.0], [1.0, 2.0, -5.0], 2.0, GLASS, [GLASS_BOX])
    assert "C" in warprt.render(s).stats.variant.split("_")[1]  # the culling variant
    check("single_sided_glass", s)
