"""Gradients with respect to an area light's own shape (issue 30 over issue 32's lights; issue 38): lights.<i>.center
of a rectangle, disk or sphere light, a rectangle's or disk's normal, a rectangle's size (about its normal) or
half-edges u and v, a disk's or sphere's radius. Its sample points lie at fixed places in its frame (center plus
its axes: scene.local_coordinates), so the replay moves the forward's points, normals and areas with the frame
(kernels.shape_samples, on the tape before kernels.replay_area): each the forward's plus its change, at the
frame's values the forward's to the bit. Which points each hit sees, and the emitter's face met by a ray, are
held fixed, as visibility is (their edges: backward(edges=True), tests/grad/test_shadow_edges.py). Checked:

- the replayed image is the forward's, to the bit (the points moved by 0);
- directional derivatives along random directions equal central finite differences of the forward
  (tests/grad/directional.py: pixels a moving shadow's or the emitter's edge crosses masked), for each shape
  and parameter, through a mirror's level for the rectangle;
- warp.autograd.gradcheck of the shape's frame, points, normals and areas (area_shape's functions);
- controls that fail: the points held where they are (the centre's adjoint dropped), the normals held (the
  normal's), the areas held (the size's), the gradient read along another direction.
Mitsuba's AD of the same centre (its rectangle's to_world): tests/accuracy/test_gradients_against_mitsuba.py.
"""

from __future__ import annotations

import numpy as np
import pytest
import warp as wp
import warp.autograd

import warprt
from warprt.kernels import ShapeLights, shape_area, shape_axes
from warprt.scene import resolve_effects

from .directional import backward_masked, directional, random_direction

WIDTH, HEIGHT = 24, 18
TOL = 1e-2
LIGHTS = {"rectangle": {"shape": "rectangle", "center": [0.4, 2.6, 0.3], "normal": [0.0, -1.0, 0.5], "size": [1.2, 0.8]},
          "disk": {"shape": "disk", "center": [-0.3, 2.4, 0.6], "normal": [0.2, -1.0, 0.3], "radius": 0.5},
          "sphere": {"shape": "sphere", "center": [0.6, 2.2, 0.8], "radius": 0.3},
          "edges": {"shape": "rectangle", "center": [0.4, 2.6, 0.3], "u": [0.6, 0.0, 0.1], "v": [0.0, 0.3, 0.4]}}
SHAPES = {"rectangle": ("center", "normal", "size"), "disk": ("center", "normal", "radius"),
          "sphere": ("center", "radius"), "edges": ("center", "u", "v")}


def lit(shape: str = "rectangle", max_depth: int = 2):
    """tests/grad/test_area_light_gradients.py's soft(): a glossy sphere over a glossy, weakly mirroring floor
    (``max_depth`` levels), its soft shadow in view, under one area light of ``shape`` whose front is seen."""
    return warprt.load_dict({
        "camera": {"eye": [0.0, 1.6, 5.0], "center": [0.0, 1.0, 0.0], "width": WIDTH, "height": HEIGHT},
        "render": {"ambient": [0.05] * 3, "max_depth": max_depth, "light_samples": 16},
        "lights": [{"type": "area", **LIGHTS[shape], "radiance": [6.0, 5.0, 4.0]}],
        "materials": {"floor": {"kd": [0.4, 0.35, 0.3], "ks": [0.2] * 3, "shininess": 16.0, "reflectivity": [0.3] * 3},
                      "ball": {"kd": [0.6, 0.2, 0.1], "ks": [0.5] * 3, "shininess": 40.0}},
        "objects": [{"shape": "plane", "size": [8.0, 8.0], "material": "floor"},
                    {"shape": "sphere", "subdivisions": 2, "smooth": True, "translate": [0.0, 0.8, 0.0], "scale": 0.8,
                     "material": "ball"}]})


@pytest.fixture(scope="module")
def weights():
    return np.random.default_rng(17).random((HEIGHT, WIDTH, 3)).astype(np.float32)


@pytest.mark.parametrize("shape", list(LIGHTS))
def test_the_replayed_image_is_the_forward_image(shape):
    s = lit(shape)
    r = warprt.Renderer(s)
    forward = r.render().image
    geom = r.geometry
    hits = warprt.image.record_first_hits(s, geom, geom.scene_data(s), resolve_effects(s), "cpu")
    assert np.array_equal(warprt.image.replay_image(s, geom, hits, "cpu", shapes=True), forward)
    r.close()


def shape_differences(s, weights, seed: int, name: str = "lights.0.center"):
    return directional(s, random_direction(s, [name], seed=seed, rel=0.05), weights, h=1e-2)


@pytest.mark.parametrize("shape, key", [(shape, key) for shape, keys in SHAPES.items() for key in keys])
def test_the_shape_equals_central_differences(weights, shape, key):
    s = lit(shape, max_depth=2 if shape == "rectangle" else 1)
    d = shape_differences(s, weights, 3, f"lights.0.{key}")
    assert d.masked < 0.1
    g = backward_masked(s, weights, d)
    assert d.error(g) <= TOL, (d.gradient(g), d.fd)
    other = shape_differences(s, weights, 4, f"lights.0.{key}")  # the control: read along another direction
    assert abs(other.gradient(g) - d.fd) > 0.1 * abs(d.fd)


def _held(replay, hits, what: str):
    """The replay with the area lights' sample ``what`` (points, normals, dA) held where the forward put them."""
    area = replay.data.area
    setattr(area, what, getattr(hits.data.area, what))
    replay.data.area = area  # a nested Warp struct is held by value: set again


@pytest.mark.parametrize("key, what", [("center", "points"), ("normal", "normals"), ("size", "dA")])
def test_a_shape_whose_samples_are_held_is_not_the_differences(weights, key, what):
    """The controls: the replay with the sample points, their normals or their areas held where the forward put
    them (replay_area reading the forward's) misses the centre's, the normal's or the size's term; unedited,
    the hand-launched replay is backward()'s."""
    s = lit()
    name = f"lights.0.{key}"
    d = shape_differences(s, weights, 3, name)

    def taped(held: bool) -> np.ndarray:
        r = warprt.Renderer(s)
        r.render()
        geom = r.geometry
        hits = warprt.image.record_first_hits(s, geom, geom.scene_data(s), resolve_effects(s), "cpu")
        replay = warprt.image.build_replay(s, geom, hits, "cpu", shapes=True)
        if held:
            _held(replay, hits, what)
        tape = wp.Tape()
        with tape:
            replay.launch()
        tape.backward(grads={replay.colour: wp.array((weights * d.mask).reshape(-1, 3), dtype=wp.vec3)})
        r.close()
        return np.asarray(getattr(replay.arrays["shape"].lights, key).grad.numpy()[0], np.float64)

    right = taped(held=False)
    np.testing.assert_allclose(right, backward_masked(s, weights, d)[name], rtol=1e-6, atol=1e-6)
    assert d.error({name: right}) <= TOL
    assert d.error({name: taped(held=True)}) > 0.1


@wp.kernel
def _frame(kind: wp.array(dtype=int), by_edges: wp.array(dtype=int), center: wp.array(dtype=wp.vec3),
           normal: wp.array(dtype=wp.vec3), size: wp.array(dtype=wp.vec2), radius: wp.array(dtype=float),
           u: wp.array(dtype=wp.vec3), v: wp.array(dtype=wp.vec3), light: wp.array(dtype=int),
           local: wp.array(dtype=wp.vec3), point: wp.array(dtype=wp.vec3), normals: wp.array(dtype=wp.vec3),
           area: wp.array(dtype=float)):
    """Per point (of the shape light ``light[q]``) its place in the light's frame, made from the parameters,
    with the light's normal (A x B, unit) and area: what shape_samples moves the forward's by."""
    q = wp.tid()
    lights = ShapeLights()
    lights.kind = kind
    lights.by_edges = by_edges
    lights.center = center
    lights.normal = normal
    lights.size = size
    lights.radius = radius
    lights.u = u
    lights.v = v
    i = light[q]
    axes = shape_axes(lights, i)
    point[q] = lights.center[i] + local[q][0] * axes[0] + local[q][1] * axes[1] + local[q][2] * axes[2]
    normals[q] = wp.normalize(wp.cross(axes[0], axes[1]) + wp.vec3(0.0, 0.0, 1.0e-3))
    area[q] = shape_area(lights, i)


def test_the_shape_functions_pass_warps_gradcheck():
    """shape_axes and shape_area's adjoints in a rectangle's center, normal and size, a rectangle's u and v, a
    disk's normal and radius, a sphere's radius, against Warp's own finite differences at points of each."""
    vec = lambda rows, t=wp.vec3: wp.array(np.asarray(rows, np.float32), dtype=t, requires_grad=True)  # noqa: E731
    inputs = [wp.array([0, 0, 1, 2], dtype=int), wp.array([0, 1, 0, 0], dtype=int),
              vec([[0.4, 2.6, 0.3], [0.1, 2.0, 0.0], [-0.3, 2.4, 0.6], [0.6, 2.2, 0.8]]),
              vec([[0.1, -1.0, 0.5], [0.0, 0.0, 1.0], [0.2, -1.0, 0.3], [0.0, 0.0, 1.0]]),
              vec([[1.2, 0.8], [0.0, 0.0], [0.0, 0.0], [0.0, 0.0]], wp.vec2),
              wp.array([0.0, 0.0, 0.5, 0.3], dtype=float, requires_grad=True),
              vec([[0.0] * 3, [0.6, 0.0, 0.1], [0.0] * 3, [0.0] * 3]), vec([[0.0] * 3, [0.0, 0.3, 0.4], [0.0] * 3, [0.0] * 3]),
              wp.array(np.repeat(np.arange(4), 3).astype(np.int32), dtype=int),
              vec(np.random.default_rng(2).uniform(-1.0, 1.0, (12, 3)) * [1.0, 1.0, 0.0] + [0.0, 0.0, 0.0])]
    outputs = [wp.zeros(12, dtype=wp.vec3, requires_grad=True), wp.zeros(12, dtype=wp.vec3, requires_grad=True),
               wp.zeros(12, dtype=float, requires_grad=True)]
    assert warp.autograd.gradcheck(_frame, dim=12, inputs=inputs, outputs=outputs, eps=1e-3, atol=2e-3, rtol=2e-3,
                                   show_summary=False, raise_exception=False)


def test_only_a_shape_lights_shape_is_a_parameter():
    """A shape light's shape is r.params names backward() differentiates, as the light has them; an object light
    (Mitsuba's Cornell box's) has none: its points follow its object's vertices, held fixed."""
    for shape, keys in SHAPES.items():
        r = warprt.Renderer(lit(shape))
        names = [f"lights.0.{k}" for k in keys]
        assert {n for n in r.params if n.startswith("lights.") and not n.endswith(".radiance")} == set(names)
        r.render(grad=True)
        assert set(r.backward(np.ones((HEIGHT, WIDTH, 3), np.float32), wrt=names)) == set(names)
        r.close()
    from .test_area_light_gradients import cornell

    r = warprt.Renderer(cornell(4))
    assert "lights.0.center" not in r.params
    r.render(grad=True)
    with pytest.raises(warprt.SceneError, match="lights.0.center"):  # ArgumentError is one
        r.backward(np.ones((24, 24, 3), np.float32), wrt=["lights.0.center"])
    r.close()
