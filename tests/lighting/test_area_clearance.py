"""Area lights' shadow rays skipped where a hit is proven to see the whole light (kernels/clearance.py,
shadow_query "auto"): the image is the one with every shadow ray traced (shadow_query "bvh"), to the bit, on
scenes built to stress the proof (an occluder's corners outside the light's pyramid on both sides of it, a
ceiling in the light's own plane, a wall touching the light's edge, a tilted light, curved occluders), for
each estimator, spread or not, with a Phong highlight; and fewer shadow rays are traced where a light has a hull
(a sphere light has none: every ray traced)."""

from __future__ import annotations

import numpy as np
import pytest

import warprt

MATERIALS = {"white": {"kd": [0.5, 0.5, 0.5], "ks": [0.0] * 3},
             "shiny": {"kd": [0.3, 0.4, 0.5], "ks": [0.4] * 3, "shininess": 20.0},
             "plate": {"kd": [0.0] * 3, "ks": [0.0] * 3}}
ROOM = [
    {"shape": "plane", "size": [6.0, 6.0], "material": "shiny"},  # floor, y = 0
    {"shape": "plane", "size": [6.0, 6.0], "rotate": [180.0, 0.0, 0.0], "translate": [0.0, 2.0, 0.0],
     "material": "white"},  # ceiling, facing down, in a rectangle light's plane
    {"shape": "plane", "size": [6.0, 3.0], "rotate": [90.0, 0.0, 0.0], "translate": [0.0, 1.0, -1.5],
     "material": "white"},  # back wall
    {"shape": "plane", "size": [3.0, 6.0], "rotate": [0.0, 0.0, -90.0], "translate": [-1.0, 1.0, 0.0],
     "material": "white"},  # a left wall, x = -1
    {"shape": "box", "size": [0.4, 0.6, 0.4], "rotate": [0.0, 30.0, 0.0], "translate": [0.6, 0.3, 0.3],
     "material": "shiny"},
    # a bar across the light's pyramid whose corners all lie outside it, on both sides
    {"shape": "box", "size": [1.6, 0.05, 0.05], "translate": [0.5, 1.2, 0.0], "material": "white"},
    {"shape": "sphere", "radius": 0.25, "smooth": True, "translate": [1.2, 0.25, -0.6], "material": "white"},
]
LIGHTS = {
    "rectangle": {"type": "area", "radiance": [3.0] * 3, "shape": "rectangle", "center": [0.0, 2.0, 0.0],
                  "u": [0.5, 0.0, 0.0], "v": [0.0, 0.0, 0.4]},  # faces down (u x v)
    "tilted rectangle": {"type": "area", "radiance": [3.0] * 3, "shape": "rectangle", "center": [0.3, 1.7, 0.2],
                         "u": [0.4, 0.1, 0.0], "v": [0.0, 0.05, 0.3]},
    "disk": {"type": "area", "radiance": [3.0] * 3, "shape": "disk", "center": [0.2, 1.8, 0.0],
             "normal": [0.0, -1.0, 0.0], "radius": 0.35},
    "flat object": {"type": "area", "radiance": [3.0] * 3, "object": "lamp"},
    "sphere": {"type": "area", "radiance": [3.0] * 3, "shape": "sphere", "center": [0.2, 1.6, 0.0], "radius": 0.2},
}
LAMP = {"shape": "plane", "name": "lamp", "size": [0.6, 0.5], "rotate": [180.0, 0.0, 0.0],
        "translate": [0.1, 1.9, 0.1], "material": "plate"}


def room(light: str, **render) -> warprt.Scene:
    objects = ROOM + ([LAMP] if light == "flat object" else [])
    return warprt.load_dict({
        "camera": {"eye": [2.6, 1.6, 2.8], "center": [0.2, 0.5, -0.2], "fovy": 55.0, "width": 40, "height": 30},
        "render": {"ambient": [0.05] * 3, "light_samples": 16, "max_depth": 2, **render},
        "lights": [LIGHTS[light]], "materials": MATERIALS, "objects": objects})


def both(scene):
    """(every shadow ray traced, the proof's shortcut): each frame's image and shadow rays."""
    out = []
    for query in ("bvh", "auto"):
        result = warprt.render(scene, primary_query="raytrace", shadow_query=query)
        out.append((result.image, result.stats.rays["shadow"]))
    return out


@pytest.mark.parametrize("light", list(LIGHTS))
def test_the_proven_hits_image_is_the_traced_one_to_the_bit(light):
    (traced, traced_rays), (proven, proven_rays) = both(room(light))
    assert np.array_equal(traced, proven), np.argwhere((traced != proven).any(axis=-1))[:5]
    if light == "sphere":
        assert proven_rays == traced_rays  # no hull: nothing to prove with
    else:
        assert proven_rays < 0.9 * traced_rays, (proven_rays, traced_rays)


@pytest.mark.parametrize("estimator, spp, spread", [("analytic", 1, False), ("samples", 4, True),
                                                    ("analytic", 4, True)])
def test_each_estimator_keeps_the_traced_image(estimator, spp, spread):
    """The analytic estimator skips a proven light's points too (its ratio is then 1 exactly); with a
    highlight (the floor is shiny) the points stay, without their rays."""
    scene = room("rectangle", area_estimator=estimator, spp=spp, light_spread=spread)
    (traced, traced_rays), (proven, proven_rays) = both(scene)
    assert np.array_equal(traced, proven), np.argwhere((traced != proven).any(axis=-1))[:5]
    assert proven_rays < 0.9 * traced_rays


def test_a_proof_that_skipped_every_ray_would_be_seen():
    """Negative control: the room's shadows (the bar's, the box's, the wall's) cover enough pixels that an
    image with the rays skipped everywhere is not the traced one."""
    scene = room("rectangle")
    (traced, _), _ = both(scene)
    unshadowed = warprt.render(scene, primary_query="raytrace", disable=["shadows"]).image
    assert (traced != unshadowed).any(axis=-1).sum() > 100


def test_a_gradient_frames_record_is_the_traced_ones():
    """render(grad=True) takes the proof too (the record's bit per point seen is the same whether the ray was
    traced or the light proven clear): the image, and the derivative of a loss in the light's radiance and the
    box's vertices (edges included), are the ones with every shadow ray traced, to the bit."""
    scene = room("rectangle")
    weights = np.random.default_rng(3).uniform(0.0, 1.0, (30, 40, 3)).astype(np.float32)
    got = []
    for query in ("bvh", "auto"):
        r = warprt.Renderer(scene, primary_query="raytrace", shadow_query=query)
        names = [n for n in r.params if n.endswith(".radiance") or n == "objects.4.vertices"]
        result = r.render(grad=True)
        got.append((result.image, result.stats.rays["shadow"], r.backward(weights, wrt=names)))
    (traced, traced_rays, g_traced), (proven, proven_rays, g_proven) = got
    assert len(g_traced) == 2 and proven_rays < 0.9 * traced_rays
    assert np.array_equal(traced, proven)
    for name in g_traced:
        assert np.array_equal(g_traced[name], g_proven[name]) and np.abs(g_traced[name]).max() > 0.0, name
