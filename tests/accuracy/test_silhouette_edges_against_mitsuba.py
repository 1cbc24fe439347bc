"""backward(edges=True) against Mitsuba 3's direct_projective (issue 38's reference for silhouettes;
reference/mitsuba_projective.py): a diffuse triangle under a directional light on a black background, and
the same triangle in front of a second one whose edge it partly hides, the gradient in each object's
vertices, every component. Mitsuba samples the silhouettes at random (32 passes of 256 samples a pixel);
warprt integrates them at fixed points. Measured: every component within 0.045 of Mitsuba's mean (0.24% of the
largest component, 16 to 22; at most 3.8 of Mitsuba's standard errors), the images within 4e-4 on average;
the control, warprt's interior derivative alone, is off by 16 to 22.
"""

from __future__ import annotations

import numpy as np
import pytest

import warprt
from reference.mitsuba_projective import projective_vertex_gradients

pytestmark = pytest.mark.accuracy

WIDTH, HEIGHT = 24, 18
TRIANGLE = [[-1.0, -0.8, 0.0], [1.1, -0.6, 0.2], [0.1, 0.9, -0.1]]
BEHIND = [[-1.8, -1.2, -1.0], [0.4, -1.4, -1.1], [-0.6, 1.2, -1.2]]


def scene(behind: bool):
    """The triangle (facing the camera and the light), with ``behind`` a second one it partly hides. Mitsuba's
    direct light is shadowed; the light along the view axis casts the triangle's shadow within the part of
    the other the camera does not see, so that warprt's model without shadows is Mitsuba's."""
    objects = [{"shape": "triangles", "name": "tri", "vertices": TRIANGLE, "faces": [[0, 1, 2]], "material": "m"}]
    if behind:
        objects.append({"shape": "triangles", "name": "back", "vertices": BEHIND, "faces": [[0, 1, 2]],
                        "material": "n"})
    return warprt.load_dict({
        "camera": {"eye": [0.0, 0.0, 4.0], "center": [0.0, 0.0, 0.0], "width": WIDTH, "height": HEIGHT, "fovy": 40.0},
        "render": {"ambient": [0.0] * 3, "max_depth": 1, "shadows": False, "spp": 256, "background": [0.0] * 3},
        "lights": [{"type": "directional", "direction": [0.0, 0.0, -1.0], "color": [0.9, 0.8, 0.7]}],
        "materials": {"m": {"kd": [0.7, 0.4, 0.2], "ks": [0.0] * 3}, "n": {"kd": [0.2, 0.5, 0.6], "ks": [0.0] * 3}},
        "objects": objects})


@pytest.mark.parametrize("behind, name", [(False, "tri"), (True, "tri"), (True, "back")],
                         ids=["against the background", "in front of another", "partly hidden"])
def test_the_edges_gradient_equals_mitsubas_direct_projective(behind, name):
    s = scene(behind)
    weights = np.random.default_rng(11).random((HEIGHT, WIDTH, 3)).astype(np.float32)
    r = warprt.Renderer(s)
    r.render(grad=True)
    wrt = [f"objects.{name}.vertices"]
    ours, interior = r.backward(weights, wrt=wrt, edges=True)[wrt[0]], r.backward(weights, wrt=wrt, edges=False)[wrt[0]]
    r.close()
    mean, stderr = projective_vertex_gradients(s, weights, name)
    scale = np.abs(mean).max()
    assert np.all(np.abs(ours - mean) <= 4 * stderr + 4e-3 * scale), (ours, mean, stderr)
    assert np.abs(interior - mean).max() > 0.2 * scale
