"""Vertex gradients beyond the camera rays' first hits (issue 30): objects.<name>.vertices through mirror rays
(the mirror ray leaves the moved hit along the direction reflected about the moved normal, and the face it met
is re-intersected from there), checked against central finite differences of the forward along random
directions (tests/grad/directional.py: the pixels whose differences at h and h/2 disagree, an edge crossing
them, masked out), with controls that fail. Mitsuba's AD of the same vertices through its own spawn_ray:
tests/accuracy/test_gradients_against_mitsuba.py.
"""

from __future__ import annotations

import numpy as np
import pytest

import warprt

from .directional import backward_masked, directional, random_direction

WIDTH, HEIGHT = 24, 18
TOL = 1e-2
# A two-triangle floor reaching beyond the view, tilted a little (test_first_hit_gradients' TILT): moving its
# vertices turns it, so the rays it mirrors turn, with no crease or edge of it in view.
TILT = [[-20.0, 0.0, -20.0], [20.0, 0.4, -20.0], [20.0, 0.4, 20.0], [-20.0, 0.0, 20.0]]
WALL = [[-20.0, -1.0, -3.0], [20.0, -1.0, -3.0], [20.0, 20.0, -3.0], [-20.0, 20.0, -3.0]]  # behind the box
LIGHTS = [{"position": [2.0, 4.0, 3.0], "color": [0.8, 0.8, 0.7]},
          {"position": [-3.0, 2.5, 1.0], "color": [6.0, 5.0, 4.0], "falloff": "inverse_square"}]


def mirror_scene(max_depth: int = 3):
    """The tilted floor, a mirror (k_r (0.5, 0.4, 0.3)), and a turned box on it seen directly and in the
    floor; two lights, shadows; three ray levels."""
    return warprt.load_dict({
        "camera": {"eye": [0.0, 4.0, 3.0], "center": [0.0, 0.5, 0.0], "width": WIDTH, "height": HEIGHT},
        "render": {"ambient": [0.2] * 3, "max_depth": max_depth}, "lights": LIGHTS,
        "materials": {"floor": {"kd": [0.4, 0.35, 0.3], "ks": [0.2] * 3, "shininess": 16.0,
                                "reflectivity": [0.5, 0.4, 0.3]},
                      "wall": {"kd": [0.3, 0.5, 0.6], "ks": [0.3] * 3, "shininess": 8.0},
                      "crate": {"kd": [0.6, 0.2, 0.1], "ks": [0.5] * 3, "shininess": 40.0}},
        "objects": [{"shape": "triangles", "name": "floor", "vertices": TILT, "faces": [[0, 1, 2], [0, 2, 3]],
                     "material": "floor"},
                    {"shape": "box", "name": "crate", "translate": [0.0, 0.5, 0.0], "rotate": [10.0, 30.0, 5.0],
                     "material": "crate"},
                    {"shape": "triangles", "name": "wall", "vertices": WALL, "faces": [[0, 1, 2], [0, 2, 3]],
                     "material": "wall"}]})


@pytest.fixture(scope="module")
def weights():
    return np.random.default_rng(11).random((HEIGHT, WIDTH, 3)).astype(np.float32)


@pytest.fixture(scope="module")
def floor_differences(weights):
    s = mirror_scene()
    return directional(s, random_direction(s, ["objects.floor.vertices"], seed=5, rel=0.01), weights, h=1e-2)


def test_the_mirrors_vertices_through_mirror_rays_equal_central_differences(weights, floor_differences):
    """The floor's own vertices: the camera rays' hits slide over it and its normal turns, so every mirror
    ray leaves from elsewhere along another direction and meets the box or the background elsewhere."""
    d = floor_differences
    assert d.masked < 0.1
    assert d.error(backward_masked(mirror_scene(), weights, d)) <= TOL


def test_the_mirror_rays_held_are_not_the_differences(weights, floor_differences):
    """The control: the mirror rays held where they were (the levels after the first do not follow the
    floor's vertices) is the gradient of the first level alone, the same frame at max_depth 1 (its camera
    rays' hits and shading the same; the mirrored colours then constants in the floor's vertices)."""
    d = floor_differences
    held = backward_masked(mirror_scene(max_depth=1), weights, d)
    assert d.error(held) > 0.1


@pytest.mark.parametrize("names", [["objects.crate.vertices"], ["objects.floor.vertices", "objects.crate.vertices"]],
                         ids=["box", "both"])
def test_an_object_seen_in_the_mirror_equals_central_differences(weights, names):
    """The box's vertices (seen directly and in the floor: its mirror rays' hits re-intersected on its moved
    faces), and both objects at once; the box's silhouette moves, its pixels masked out."""
    s = mirror_scene()
    d = directional(s, random_direction(s, names, seed=7, rel=0.01), weights, h=1e-2)
    assert d.masked < 0.1
    g = backward_masked(s, weights, d)
    assert d.error(g) <= TOL
    other = directional(s, random_direction(s, names, seed=8, rel=0.01), weights, h=1e-2)  # the control
    assert abs(other.gradient(g) - d.fd) > 0.1 * abs(d.fd)
