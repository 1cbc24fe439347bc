"""Switching an effect off changes nothing else: the images differ only where that effect acts."""

from dataclasses import replace
from pathlib import Path

import numpy as np

import warprt
from warprt.scene import Material, RenderSettings
from scenekit import make_scene
from oracle import camera_rays, ray_plane

MAT = {"ka": [0.2, 0.1, 0.05], "kd": [0.5, 0.6, 0.7], "ks": [0.3, 0.4, 0.5], "shininess": 20.0}
LIGHT = np.array([0.0, 0.0, 4.0])
WALL = {"shape": "plane", "size": [20.0, 20.0], "rotate": [90.0, 0.0, 0.0], "material": "m"}
OCCLUDER = {"shape": "plane", "size": [1.0, 1.0], "rotate": [90.0, 0.0, 0.0], "translate": [0.2, 0.1, 2.0], "material": "m"}


def test_shadows_off_equals_shadows_on_wherever_no_shadow_falls():
    scene = make_scene([WALL, OCCLUDER], {"m": MAT}, [{"position": LIGHT.tolist()}, {"position": [3.0, -2.0, 6.0]}],
                       ambient=[0.1, 0.2, 0.3], camera={"eye": [0.0, 0.0, 8.0], "width": 80, "height": 80})
    on, s_on = warprt.render(scene)
    off, s_off = warprt.render(scene, disable=["shadows"])
    assert s_on.variant != s_off.variant and s_off.rays["shadow"] == 0
    # Where a wall point's segment to either light crosses the occluder square (z = 2), a shadow falls.
    o, d = camera_rays(scene.camera)
    p = o + ray_plane(o, d, [0, 0, 0], np.array([0.0, 0.0, 1.0]))[..., None] * d
    shadowed = np.zeros(p.shape[:2], bool)
    for light in (LIGHT, np.array([3.0, -2.0, 6.0])):
        s = (2.0 - p[..., 2]) / (light[2] - p[..., 2])
        c = p + s[..., None] * (light - p)
        shadowed |= np.maximum(np.abs(c[..., 0] - 0.2), np.abs(c[..., 1] - 0.1)) <= 0.5 + 1e-3
    assert shadowed.sum() > 100 and (~shadowed).sum() > 1000
    assert np.array_equal(on[~shadowed], off[~shadowed])
    # ...and inside the shadows, switching them off only adds light.
    assert (off[shadowed] >= on[shadowed]).all() and (off[shadowed] > on[shadowed]).any()


def test_reflection_off_changes_only_reflective_pixels():
    scene = warprt.load_scene().with_camera(width=64, height=48)
    on, _ = warprt.render(scene)
    off, s_off = warprt.render(scene, disable=["reflection"])
    assert s_off.rays["reflection"] == 0
    # The primary hit's material, from an ambient-only render with one marker colour per material.
    markers = {name: Material(kd=(0, 0, 0), ka=(i + 1.0, 0, 0)) for i, name in enumerate(scene.materials)}
    ids, _ = warprt.render(replace(scene, lights=[], materials=markers,
                                   render=RenderSettings(ambient=(1.0, 1.0, 1.0), max_depth=1)))
    reflective = {i + 1.0 for i, m in enumerate(scene.materials.values()) if max(m.reflectivity) > 0}
    matte = ~np.isin(ids[..., 0], list(reflective))
    assert matte.sum() > 100 and (~matte).sum() > 100
    assert np.array_equal(on[matte], off[matte])
    assert not np.array_equal(on[~matte], off[~matte])


def test_refraction_off_changes_only_pixels_that_see_glass():
    """With refraction off a dielectric is an opaque surface: only pixels whose camera ray meets glass
    change (the glass casts the same hard shadow either way)."""
    scene = warprt.load_scene(Path(__file__).resolve().parents[2] / "scenes" / "glass_sphere.toml",
                              {"camera.width": 64, "camera.height": 48})
    on, s_on = warprt.render(scene)
    off, s_off = warprt.render(scene, disable=["refraction"])
    assert s_on.rays["refraction"] > 0 and s_off.rays["refraction"] == 0
    markers = {name: Material(kd=(0, 0, 0), ka=(float(m.dielectric), 0, 0)) for name, m in scene.materials.items()}
    glass, _ = warprt.render(replace(scene, lights=[], materials=markers,
                                     render=RenderSettings(ambient=(1.0, 1.0, 1.0), max_depth=1)))
    sees_glass = glass[..., 0] > 0
    assert sees_glass.sum() > 100 and (~sees_glass).sum() > 100
    assert np.array_equal(on[~sees_glass], off[~sees_glass])
    assert not np.array_equal(on[sees_glass], off[sees_glass])
