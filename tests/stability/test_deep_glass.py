"""Deep ray trees stay finite and bounded: up to max_depth 65 (the largest stack) inside a glass slab
the image equals the closed form B (1 - F^(max_depth - 1)) and the work is exactly one reflected and
one refracted ray per level; between two slabs, where every branch goes on, the rays per sample stay
within the tree's 2^max_depth - 1; beyond 65 levels a glass scene is refused, naming the field."""

import math

import numpy as np
import pytest

import warprt
from marks import slow
from oracle import optics
from oracle import camera_rays
from scenekit import make_scene
from warprt.kernels import MAX_TREE_DEPTH

from stability.probes import record

ETA = 1.5
GLASS = {"ior": ETA, "ka": [0.0] * 3, "kd": [0.0] * 3}
B = [0.2, 0.5, 0.8]


def inside_a_slab(max_depth, W=8, H=6):
    """The eye inside a glass slab 2 thick, looking at its top face 40.3 to 41.3 degrees from the normal,
    just under the critical angle (41.8): every hit lets 1 - F of the ray out into the background and
    reflects F back in, F from 0.27 to 0.45, so that after 64 reflections F^64 is still a float32."""
    a = math.radians(40.8)
    camera = {"eye": [0.0, 0.0, 0.0], "center": [0.0, math.cos(a), -math.sin(a)], "up": [0.0, 1.0, 0.0],
              "fovy": 1.0, "width": W, "height": H}
    box = {"shape": "box", "size": [2000.0, 2.0, 2000.0], "material": "glass"}
    return make_scene([box], {"glass": GLASS}, camera=camera, background=B, max_depth=max_depth)


@slow
@pytest.mark.parametrize("max_depth", [32, MAX_TREE_DEPTH])
def test_deep_inside_a_glass_slab_the_image_is_the_closed_form_and_the_work_linear(max_depth):
    scene = inside_a_slab(max_depth)
    r = warprt.render(scene, report_truncated=True)
    _, d = camera_rays(scene.camera)
    F = optics.fresnel(np.abs(d[..., 1]), ETA, 1.0)  # the same angle at every face: they are parallel
    out = 1.0 - F ** (max_depth - 1)
    assert np.isfinite(r.image).all()
    assert np.allclose(r.image, np.asarray(B) * out[..., None], rtol=1e-5, atol=1e-7)
    # F^(max_depth - 1) multiplies float32's error in F (1e-5 of it, this near the critical angle) by max_depth - 1.
    assert np.allclose(r.stats.truncated, (F ** (max_depth - 1))[..., None], rtol=2e-5 * max_depth, atol=1e-30)
    W, H = scene.camera.width, scene.camera.height
    assert r.stats.rays == {"primary": W * H, "shadow": 0, "reflection": (max_depth - 1) * W * H,
                            "refraction": (max_depth - 1) * W * H, "total": (2 * max_depth - 1) * W * H}
    record(f"deep_glass/slab max_depth {max_depth}", {**r.stats.rays, "max_truncated": float(r.stats.truncated.max())})


def test_between_two_slabs_every_branch_goes_on_within_the_trees_bound():
    max_depth, W, H = 12, 4, 4
    slabs = [{"shape": "box", "size": [400.0, 400.0, 1.0], "translate": [0.0, 0.0, z], "material": "glass"} for z in (-2.5, 2.5)]
    scene = make_scene(slabs, {"glass": GLASS}, camera={"eye": [0.0, 0.0, 0.0], "center": [0.0, 0.0, -1.0], "fovy": 10.0,
                                                          "width": W, "height": H}, background=B, max_depth=max_depth)
    r = warprt.render(scene, report_truncated=True)
    total = r.stats.rays["total"]
    assert np.isfinite(r.image).all()
    assert 2 * max_depth * W * H < total <= (2**max_depth - 1) * W * H  # it branches, and no more than a tree can
    # Nothing is absorbed: what did not get out was cut off by max_depth.
    assert np.allclose(r.image + np.asarray(B) * r.stats.truncated, B, atol=2e-6)
    record("deep_glass/two slabs", {**r.stats.rays, "bound": (2**max_depth - 1) * W * H})


def test_a_glass_scene_deeper_than_the_stack_is_refused():
    with pytest.raises(warprt.SceneError) as e:
        warprt.render(inside_a_slab(MAX_TREE_DEPTH + 1))
    assert e.value.field == "render.max_depth" and f"at most {MAX_TREE_DEPTH} ray levels" in e.value.message
    # Without glass the same depth is fine: mirrors need no stack.
    mirror = make_scene([{"shape": "plane", "material": "m"}], {"m": {"reflectivity": 0.5}}, max_depth=MAX_TREE_DEPTH + 1)
    assert warprt.render(mirror.with_camera(width=4, height=3)).stats.max_depth == MAX_TREE_DEPTH + 1
