"""Vertex gradients beyond the camera rays' first hits (issue 30): objects.<name>.vertices through mirror rays
(the mirror ray leaves the moved hit along the direction reflected about the moved normal, and the face it met
is re-intersected from there), checked against central finite differences of the forward along random
directions (tests/grad/directional.py: the pixels whose differences at h and h/2 disagree, an edge crossing
them, masked out), with controls that fail. Mitsuba's AD of the same vertices through its own spawn_ray:
tests/accuracy/test_gradients_against_mitsuba.py.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
import warp as wp
import warp.autograd

import warprt
from warprt.kernels import smooth_vertex_normals, vertex_normal_sums
from warprt.scene import resolve_effects, vertex_normals

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


# --- Smooth objects: the vertex normals move with the vertices -------------------------------------------

def smooth_scene(smooth=True):
    """A glossy smooth sphere (an icosphere: one vertex per position) on a flat floor, its highlights in view,
    both lights on the camera's side so that no terminator crosses it in view (where n.L crosses 0 a light's
    term starts with a kink the held visibility leaves out); shadows on the floor. ``smooth``: True, normals
    computed from the triangles (they follow the vertices); a crease angle, the scene's own normals, computed
    once when it is loaded (they stay when the vertices move, as a file's do)."""
    return warprt.load_dict({
        "camera": {"eye": [0.3, 1.6, 3.0], "center": [0.0, 0.6, 0.0], "width": WIDTH, "height": HEIGHT, "fovy": 35.0},
        "render": {"ambient": [0.2] * 3, "max_depth": 1},
        "lights": [{"position": [1.5, 3.0, 3.0], "color": [0.8, 0.8, 0.7]},
                   {"position": [-1.0, 2.5, 3.5], "color": [9.0, 8.0, 7.0], "falloff": "inverse_square"}],
        "materials": {"floor": {"kd": [0.4, 0.35, 0.3], "ks": [0.2] * 3, "shininess": 16.0},
                      "ball": {"kd": [0.6, 0.2, 0.1], "ks": [0.8] * 3, "shininess": 30.0}},
        "objects": [{"shape": "plane", "name": "floor", "size": [30.0, 30.0], "material": "floor"},
                    {"shape": "sphere", "name": "ball", "subdivisions": 2, "smooth": smooth, "translate": [0.0, 0.7, 0.0],
                     "scale": 0.7, "material": "ball"}]})


def ball_differences(s, weights):
    """Central differences along a random direction of the sphere's vertices (steps of 1e-3 of its scale):
    a triangle's edge crossing a camera ray bends its pixel's differences (the hits held on their faces have
    no term for it), so the pixels whose face changes are masked out too (same_faces)."""
    return directional(s, random_direction(s, ["objects.ball.vertices"], seed=7, rel=0.2), weights, h=5e-3,
                       same_faces=True)


@pytest.mark.parametrize("smooth", [True, 30.0], ids=["computed normals", "the scene's normals"])
def test_a_smooth_objects_vertices_equal_central_differences(weights, smooth):
    """The hit slides over the moved face, and the interpolated normal it is shaded with turns with the
    vertex normals (computed ones) or stays interpolated from the fixed ones (the scene's own)."""
    s = smooth_scene(smooth)
    assert (s.objects[1].normals is None) == (smooth is True)
    d = ball_differences(s, weights)
    assert d.masked < 0.1
    assert d.error(backward_masked(s, weights, d)) <= TOL


def _taped_vertices(s, weights, mask, hold_normals: bool) -> np.ndarray:
    """The sphere's vertex adjoints from the replay launched by hand (warprt.image.build_replay with the
    vertices); with ``hold_normals``, the launches that make the normals from the points dropped and the
    forward's normals given instead: the control's wrong model."""
    r = warprt.Renderer(s)
    r.render()
    geom = r.geometry
    hits = warprt.image.record_first_hits(s, geom, geom.scene_data(s), resolve_effects(s), "cpu")
    replay = warprt.image.build_replay(s, geom, hits, "cpu", vertices=True)
    if hold_normals:
        replay.before, replay.data.normals = [], geom.normals
    tape = wp.Tape()
    with tape:
        replay.launch()
    tape.backward(grads={replay.colour: wp.array((weights * mask).reshape(-1, 3), dtype=wp.vec3)})
    r.close()
    return replay.arrays["points"].grad.numpy().astype(np.float64)[len(s.objects[0].vertices):]


def test_the_normals_held_are_not_the_differences(weights):
    """The control: the same replay with the vertex normals held at the forward's (their adjoint dropped)
    misses the turning normal's term; unedited, the hand-launched replay is backward()'s."""
    s = smooth_scene()
    d = ball_differences(s, weights)
    right = _taped_vertices(s, weights, d.mask, hold_normals=False)
    np.testing.assert_allclose(right, backward_masked(s, weights, d)["objects.ball.vertices"], rtol=1e-6, atol=1e-6)
    wrong = _taped_vertices(s, weights, d.mask, hold_normals=True)
    assert d.error({"objects.ball.vertices": right}) <= TOL
    assert d.error({"objects.ball.vertices": wrong}) > 0.1


def test_the_replayed_normals_are_the_forwards():
    """The normals the replay makes from the points (float32, Warp) are the forward's (normals.vertex_normals,
    NumPy float64, angle-weighted) to float32 rounding, on a sphere and on a mesh whose uv seam splits vertices
    (shared by position); a crease's normals, the scene's own, are passed through."""
    seam = warprt.SceneObject.from_arrays(
        "seam", [[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 0, 0], [1, 1, 0.5], [0, 1, 0]], [[0, 1, 2], [3, 4, 5]],
        "ball", smooth=True)
    s = smooth_scene()
    s = replace(s, objects=list(s.objects) + [seam])
    r = warprt.Renderer(s)
    r.render()
    geom = r.geometry
    hits = warprt.image.record_first_hits(s, geom, geom.scene_data(s), resolve_effects(s), "cpu")
    replay = warprt.image.build_replay(s, geom, hits, "cpu", vertices=True)
    for kernel, dim, inputs, outputs in replay.before:
        wp.launch(kernel, dim=dim, inputs=inputs, outputs=outputs)
    expected = np.concatenate([vertex_normals(o.vertices, o.faces) if o.smooth else np.zeros_like(o.vertices)
                               for o in s.objects])
    np.testing.assert_allclose(replay.data.normals.numpy(), expected, atol=2e-6)
    r.close()


def test_the_normal_kernels_pass_warps_gradcheck():
    """vertex_normal_sums (the points to the angle-weighted sums) and smooth_vertex_normals (the sums
    normalised, the given normals passed through) against Warp's own finite differences, on an octahedron."""
    points = wp.array(np.asarray([[1, 0.1, 0], [-1, 0, 0.2], [0, 1, 0], [0.1, -1, 0], [0, 0, 1], [0.2, 0, -1]],
                                 np.float32), dtype=wp.vec3, requires_grad=True)
    faces = [[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]]
    indices = wp.array(np.asarray(faces, np.int32).ravel(), dtype=int)
    which = wp.array(np.arange(8, dtype=np.int32), dtype=int)
    position = wp.array(np.arange(6, dtype=np.int32), dtype=int)
    sums = wp.zeros(6, dtype=wp.vec3, requires_grad=True)
    assert warp.autograd.gradcheck(vertex_normal_sums, dim=8, inputs=[points, indices, which, position], outputs=[sums],
                                   eps=1e-3, atol=2e-3, rtol=2e-3, show_summary=False, raise_exception=False)
    given = wp.array(np.ones((7, 3), np.float32), dtype=wp.vec3)
    held = wp.array(np.r_[np.arange(6), -1].astype(np.int32), dtype=int)
    source = wp.array(np.random.default_rng(3).standard_normal((6, 3)).astype(np.float32), dtype=wp.vec3,
                      requires_grad=True)
    out = wp.zeros(7, dtype=wp.vec3, requires_grad=True)
    assert warp.autograd.gradcheck(smooth_vertex_normals, dim=7, inputs=[source, held, given], outputs=[out],
                                   eps=1e-3, atol=2e-3, rtol=2e-3, show_summary=False, raise_exception=False)
