"""Exact ray accounting against closed-form counts on scenes whose every ray is predictable."""

import numpy as np
import pytest

import warprt
from scenekit import make_scene
from oracle import camera_rays, ray_plane

W, H = 24, 16
CAM = {"eye": [0.0, 0.0, 5.0], "center": [0.0, 0.0, 0.0], "fovy": 40.0, "width": W, "height": H}
# A wall z = 0 far larger than the view: every primary ray hits it.
WALL = {"shape": "plane", "size": [400.0, 400.0], "rotate": [90.0, 0.0, 0.0], "material": "m"}
FRONT = [{"position": [1.0, 2.0, 3.0]}, {"position": [-2.0, 0.5, 1.0]}]
BEHIND = [{"position": [0.0, 0.0, -3.0]}]


def rays(objects, materials, lights=(), **render):
    scene = make_scene(objects, materials, lights, camera=CAM, ambient=[0.1] * 3, **render)
    return warprt.render(scene).stats.rays


@pytest.mark.parametrize("max_depth", [1, 2, 5])
def test_no_reflective_material_no_reflection_rays(max_depth):
    r = rays([WALL], {"m": {"kd": [0.5] * 3, "ks": [0.5] * 3}}, FRONT, max_depth=max_depth)
    assert r["reflection"] == 0 and r["primary"] == W * H


def test_shadow_rays_are_lit_hits_times_lights():
    """Both front lights have n.L > 0 at every wall point; the light behind the wall has n.L < 0
    (the normal faces the camera) and must trace no shadow ray."""
    m = {"m": {"kd": [0.5] * 3}}
    assert rays([WALL], m, FRONT)["shadow"] == W * H * 2
    assert rays([WALL], m, FRONT + BEHIND)["shadow"] == W * H * 2
    assert rays([WALL], m, BEHIND)["shadow"] == 0
    assert rays([WALL], m, FRONT, shadows=False)["shadow"] == 0


def test_shadow_rays_count_only_pixels_that_hit():
    """A wall that fills part of the view: shadow rays = (pixels whose ray hits it) x lights."""
    wall = {"shape": "plane", "size": [2.0, 1.5], "rotate": [90.0, 0.0, 0.0], "translate": [0.3, 0.2, 0.0], "material": "m"}
    scene = make_scene([wall], {"m": {"kd": [0.5] * 3}}, FRONT, camera=CAM)
    o, d = camera_rays(scene.camera)
    t = ray_plane(o, d, [0, 0, 0], np.array([0.0, 0.0, 1.0]))
    p = o + t[..., None] * d
    x, y = p[..., 0] - 0.3, p[..., 1] - 0.2
    inside = (np.abs(x) < 1.0) & (np.abs(y) < 0.75)
    edge = (np.abs(np.abs(x) - 1.0) < 1e-6) | (np.abs(np.abs(y) - 0.75) < 1e-6)
    assert not edge.any()  # no pixel centre sits on the wall's border: the count is exact
    assert warprt.render(scene).stats.rays["shadow"] == int(inside.sum()) * 2


@pytest.mark.parametrize("max_depth", [2, 3, 6])
def test_facing_mirrors_spawn_one_reflection_ray_per_level(max_depth):
    """The camera between two large facing mirrors: every ray bounces until max_depth levels are used."""
    mirror = {"kd": [0.0] * 3, "reflectivity": 0.9}
    behind = {**WALL, "translate": [0.0, 0.0, 10.0]}
    r = rays([WALL, behind], {"m": mirror}, max_depth=max_depth)
    assert r["reflection"] == W * H * (max_depth - 1)


def test_reflection_rays_start_only_on_reflective_surfaces():
    """Half of the view is a mirror, half a matte wall: reflection rays = pixels that see the mirror."""
    mirror = {"shape": "plane", "size": [200.0, 200.0], "rotate": [90, 0, 0], "translate": [-100.0 - 1e-3, 0, 0], "material": "mirror"}
    matte = {"shape": "plane", "size": [200.0, 200.0], "rotate": [90, 0, 0], "translate": [100.0, 0, 0], "material": "m"}
    scene = make_scene([mirror, matte], {"m": {"kd": [0.5] * 3}, "mirror": {"kd": [0.0] * 3, "reflectivity": 1.0}},
                       camera=CAM, max_depth=3)
    o, d = camera_rays(scene.camera)
    t = ray_plane(o, d, [0, 0, 0], np.array([0.0, 0.0, 1.0]))
    sees_mirror = (o + t[..., None] * d)[..., 0] < -1e-3
    assert 0 < sees_mirror.sum() < W * H
    assert warprt.render(scene).stats.rays["reflection"] == int(sees_mirror.sum())


def test_figure6_levels_trace_increasing_ray_totals():
    """(a) ambient, (b) + diffuse, (c) + specular shade the same primary hits: the same rays.
    (d) + shadows, (e) one reflection level, (f) two levels each trace strictly more."""
    scene = warprt.load_scene().with_camera(width=W * 2, height=H * 2)
    levels = [
        dict(effects=["ambient"]),
        dict(effects=["ambient", "diffuse", "smooth"]),
        dict(effects=["ambient", "diffuse", "specular", "smooth"]),
        dict(effects=["ambient", "diffuse", "specular", "shadows", "smooth"]),
        dict(effects=None, max_depth=2),
        dict(effects=None, max_depth=3),
    ]
    totals = []
    for level in levels:
        s = scene.with_render(max_depth=level.get("max_depth", 1))
        totals.append(warprt.render(s, effects=level["effects"]).stats.rays["total"])
    assert totals[0] == totals[1] == totals[2] == (W * 2) * (H * 2)
    assert totals[2] < totals[3] < totals[4] < totals[5]


def test_supersampling_multiplies_primary_rays():
    r = rays([WALL], {"m": {"kd": [0.5] * 3}}, FRONT, spp=9)
    assert r["primary"] == W * H * 9 and r["shadow"] == W * H * 9 * 2
