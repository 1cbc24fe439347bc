"""backward(edges=True) with shadows against Mitsuba 3's direct_projective (issue 38's reference for shadows'
edges; reference/mitsuba_projective.py): a diffuse triangle's soft shadow on a floor under a rectangle area
light, the gradient in the occluder's vertices, every component. Mitsuba samples the camera's silhouettes and
the shadows' edges (its guided indirect term) at random over its continuous emitter; warprt sums the hard
shadows of the light's 16 x 16 fixed sample points, each integrated at fixed points. Measured (16 passes of 256
samples a pixel): every component within 0.015 of Mitsuba's mean (0.8% of the largest, 1.8; at most 1.4 of its
standard errors), the images within 3.6e-4 on average; the control, the interior derivative alone, off by 1.2
times the largest. The receiver's vertices are not compared: Mitsuba's estimate of them leaves out its
shadow's edges moving with the receiver (it is warprt's less that term, within 0.013 of 11; warprt's, term
included, agrees with central differences: tests/grad/test_shadow_edges.py).
"""

from __future__ import annotations

import numpy as np
import pytest

import warprt
from reference.mitsuba_projective import projective_vertex_gradients

pytestmark = [pytest.mark.accuracy, pytest.mark.slow]

WIDTH, HEIGHT = 24, 18
FLOOR = [[-2.5, 0.0, -2.0], [2.5, 0.0, -2.2], [2.4, 0.0, 2.3], [-2.6, 0.0, 2.1]]
TRIANGLE = [[-0.7, 0.9, -0.4], [0.8, 1.0, -0.2], [0.0, 1.1, 0.7]]
K = 16  # warprt's sample points: K x K cell centres of the rectangle
TOL = 0.01  # of the largest component, besides 4 of Mitsuba's standard errors: the light's quadrature


def scene():
    """The triangle over the floor, both wound to face the camera and the light (Mitsuba's diffuse is one-sided),
    under a rectangle light out of view (Mitsuba's emitter seen directly would differ: projective_scene), on a
    black background with no ambient, shadows traced: warprt's model is Mitsuba's but for the light's
    quadrature."""
    return warprt.load_dict({
        "camera": {"eye": [0.5, 4.0, 3.5], "center": [0.0, 0.2, 0.0], "width": WIDTH, "height": HEIGHT, "fovy": 45.0},
        "render": {"ambient": [0.0] * 3, "max_depth": 1, "shadows": True, "spp": 256, "background": [0.0] * 3,
                   "light_samples": K * K},
        "lights": [{"type": "area", "shape": "rectangle", "center": [0.6, 3.0, 0.8], "normal": [0.2, -1.0, 0.1],
                    "size": [1.0, 0.8], "radiance": [4.0, 4.0, 3.5]}],
        "materials": {"floor": {"kd": [0.6, 0.6, 0.5], "ks": [0.0] * 3}, "occ": {"kd": [0.7, 0.2, 0.1], "ks": [0.0] * 3}},
        "objects": [{"shape": "triangles", "name": "floor", "vertices": FLOOR, "faces": [[0, 2, 1], [0, 3, 2]],
                     "material": "floor"},
                    {"shape": "triangles", "name": "occ", "vertices": TRIANGLE, "faces": [[0, 2, 1]], "material": "occ"}]})


@pytest.fixture(scope="module")
def warprt_gradients():
    """(weights, edges=True's, the interior's) in the occluder's vertices."""
    weights = np.random.default_rng(11).random((HEIGHT, WIDTH, 3)).astype(np.float32)
    r = warprt.Renderer(scene())
    r.render(grad=True)
    wrt = ["objects.occ.vertices"]
    ours, interior = r.backward(weights, wrt=wrt, edges=True), r.backward(weights, wrt=wrt, edges=False)
    r.close()
    return weights, ours[wrt[0]], interior[wrt[0]]


def test_the_shadow_edges_gradient_equals_mitsubas_direct_projective(warprt_gradients):
    """The occluder's vertices (its own silhouettes on the floor, and its soft shadow): every component."""
    weights, ours, interior = warprt_gradients
    mean, stderr = projective_vertex_gradients(scene(), weights, "occ", passes=16, shadows=True)
    scale = np.abs(mean).max()
    assert np.all(np.abs(ours - mean) <= 4 * stderr + TOL * scale), (ours, mean, stderr)
    assert np.abs(interior - mean).max() > 0.2 * scale
