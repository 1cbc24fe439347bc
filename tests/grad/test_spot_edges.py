"""The boundary term of a spot light's hard cone (issue 38; beam_width >= cutoff_angle, backward(edges=True),
image/grad_spot_edges.py): where the cone meets the receivers, a conic, against central differences of the
forward at 128 x 128 samples a pixel (no pixel masked), in the spot's position and direction, the receiver's
vertices, an occluder's (the cone's edge runs through its shadow) and the camera, each with the control that
the interior derivative alone (edges=False) is far off; the points on the curve and its length in the image
against a float64 construction of the cone; the curve's distance against Warp's gradcheck; the sum the same
to the bit on every run and thread count (a hard cone seen in a mirror: still refused, test_silhouette_edges.py).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import warp as wp
import warp.autograd

import warprt
from marks import exhaustive, slow
from oracle import image_point
from oracle.camera import pinhole
from oracle.geometry import ray_plane
from warprt.image import boundary
from warprt.kernels import spot_edge_distances
from warprt.scene import resolve_effects

from .converged import check_edges_term, gradient

WIDTH, HEIGHT = 24, 18
SPP = 256  # the gradient frame's: 16 x 16 strata (the differences': converged.FD_SPP)
TOL = 0.02  # measured: 0.02% to 0.42% of the differences (CASES' comments)
CONTROL = 0.3  # the interior derivative alone is off by more than this share of them (measured: 75% to 100%)
FLOOR = [[-2.5, 0.0, -2.0], [2.5, 0.0, -2.2], [2.4, 0.0, 2.3], [-2.6, 0.0, 2.1]]
OCCLUDER = [[0.6, 1.2, -0.6], [1.6, 1.25, -0.3], [0.9, 1.15, 0.6]]
SPOT = {"type": "spot", "position": [1.0, 3.0, 1.5], "target": [-0.2, 0.0, -0.1], "cutoff_angle": 25.0,
        "beam_width": 25.0, "color": [3.0, 3.0, 3.0]}  # no ramp: the cone's edge a step


def spot_scene(spp: int = SPP, shadows: bool = True, occluder: bool = True, cutoff: float = 25.0):
    """A floor under a hard spot, its cone's whole curve in view; a triangle near the light shadows a part of the
    curve (``occluder``)."""
    occ = [{"shape": "triangles", "name": "occ", "vertices": OCCLUDER, "faces": [[0, 1, 2]], "material": "occ"}]
    return warprt.load_dict({
        "camera": {"eye": [0.5, 4.0, 3.5], "center": [0.0, 0.2, 0.0], "width": WIDTH, "height": HEIGHT, "fovy": 45.0},
        "render": {"ambient": [0.1] * 3, "max_depth": 1, "shadows": shadows, "spp": spp,
                   "background": [0.1, 0.2, 0.3]},
        "lights": [{**SPOT, "cutoff_angle": cutoff, "beam_width": cutoff}],
        "materials": {"occ": {"kd": [0.6, 0.2, 0.1]}, "floor": {"kd": [0.7, 0.7, 0.6], "ks": [0.1] * 3,
                                                                "shininess": 8.0}},
        "objects": (occ if occluder else []) + [{"shape": "triangles", "name": "floor", "vertices": FLOOR,
                                                 "faces": [[0, 1, 2], [0, 2, 3]], "material": "floor"}]})


def bare_spot_scene(spp: int = SPP):
    """spot_scene without the occluder or shadow rays."""
    return spot_scene(spp, shadows=False, occluder=False)


@pytest.fixture(scope="module")
def weights():
    return np.random.default_rng(11).random((HEIGHT, WIDTH, 3)).astype(np.float32)


# measured (edges=True's error against the differences; edges=False's): the light's position 0.13% (90%), the
# occluder's vertices 0.15% (96%); without the occluder nor shadows: the position 0.05% (91%), the direction
# 0.28% (100%), the camera's eye 0.02% (100%), the floor's vertices 0.42% (75%)
CASES = [(spot_scene, "lights.0.position", 5), (spot_scene, "objects.occ.vertices", 5),
         (bare_spot_scene, "lights.0.position", 5), (bare_spot_scene, "lights.0.direction", 5),
         (bare_spot_scene, "camera.eye", 5), (bare_spot_scene, "objects.floor.vertices", 5)]
QUICK = {0}  # the rest: make test-exhaustive's alone (about 30 to 50 s each on 2 cores)


@pytest.mark.parametrize("make, name, seed", [
    pytest.param(*case, id=f"{case[0].__name__}-{case[1]}", marks=() if i in QUICK else (slow, exhaustive))
    for i, case in enumerate(CASES)])
def test_the_spot_cone_gradient_equals_central_differences(weights, make, name, seed):
    """edges=True against the differences of the converged forward, every pixel kept; the control: the
    interior derivative alone (edges=False) misses the moving cone's term by far."""
    check_edges_term(make, name, seed, weights, 4e-2, TOL, CONTROL)


def _frame(make):
    s = make()
    r = warprt.Renderer(s)
    r.render(grad=True)
    geom = r.geometry
    return r, s, boundary(s, geom, resolve_effects(s), geom.eye_offset(s.camera.eye).astype(np.float64))


def _cone_cosine(s, at: np.ndarray) -> np.ndarray:
    """Per image point, the cosine off the spot's axis of the floor point its camera ray meets (float64)."""
    c = pinhole(s.camera)
    d = (-c.d_f * c.z_e + (c.h * (at[:, 1:2] / c.height - 0.5)) * c.y_e + (c.w * (at[:, 0:1] / c.width - 0.5)) * c.x_e)
    y = c.eye + np.stack([ray_plane(c.eye, v, [0.0, 0.0, 0.0], [0.0, 1.0, 0.0]) for v in d])[:, None] * d
    axis = np.subtract(SPOT["target"], SPOT["position"])
    to = y - np.asarray(SPOT["position"])
    return (to @ axis) / np.linalg.norm(to, axis=1) / np.linalg.norm(axis)


def test_the_cone_points_lie_on_the_cone():
    """Each Gauss point, moved onto the curve, sees the floor at the cutoff angle off the spot's axis (within
    float32's rounding of the light: 1.4e-8 of the cosine, measured); the control: its chord's midpoints lie
    inside the curve, off it (3e-6)."""
    r, s, b = _frame(bare_spot_scene)
    cos = math.cos(math.radians(SPOT["cutoff_angle"]))
    assert len(b.spot.edge) > 100
    assert np.abs(_cone_cosine(s, b.spot.at) - cos).max() < 1e-7
    mid = np.stack([image_point(s.camera, q + r.geometry.origin) for q in 0.5 * (b.spots.q0 + b.spots.q1)])
    assert np.abs(_cone_cosine(s, mid) - cos).max() > 1e-6
    r.close()


def _curve_length(s, cutoff: float) -> float:
    """The image length of the cone's curve on the floor quad (the floor's edge cuts it) inside the frame, from
    200 000 points of the
    cone's circle (float64): its rays from the light met with the floor, projected."""
    apex, axis = np.asarray(SPOT["position"], np.float64), np.subtract(SPOT["target"], SPOT["position"])
    axis = axis / np.linalg.norm(axis)
    a = np.cross(axis, [1.0, 0.0, 0.0])
    a /= np.linalg.norm(a)
    b = np.cross(axis, a)
    phi = np.linspace(0.0, 2.0 * np.pi, 200_001)[:, None]
    c = math.radians(cutoff)
    rays = math.cos(c) * axis + math.sin(c) * (np.cos(phi) * a + np.sin(phi) * b)
    floor = apex + (-apex[1] / rays[:, 1:2]) * rays
    quad = np.asarray(FLOOR)[:, [0, 2]]
    edge, rel = [quad[(k + 1) % 4] - quad[k] for k in range(4)], [floor[:, [0, 2]] - quad[k] for k in range(4)]
    side = [e[0] * v[:, 1] - e[1] * v[:, 0] for e, v in zip(edge, rel)]
    on_floor = np.all(np.stack(side) >= 0.0, axis=0) | np.all(np.stack(side) <= 0.0, axis=0)
    c = pinhole(s.camera)
    d = floor - c.eye
    d = d * (c.d_f / -(d @ c.z_e))[:, None]  # oracle.image_point's, every point at once
    x = np.stack([c.width * (0.5 + (d @ c.x_e) / c.w), c.height * (0.5 + (d @ c.y_e) / c.h)], axis=1)
    seen = np.all((x >= 0.0) & (x <= [WIDTH, HEIGHT]), axis=1) & on_floor
    step = np.linalg.norm(np.diff(x, axis=0), axis=1)
    return float(step[seen[1:] & seen[:-1]].sum())


def test_the_cone_points_weigh_the_curves_length():
    """The points' weights add up to the curve's length in the image (its true arc, not its chords'); the
    control: the curve of a cone a tenth of a degree wider is longer by far more than the tolerance."""
    r, s, b = _frame(bare_spot_scene)
    total = float(b.spot.weight.sum())
    length = _curve_length(s, SPOT["cutoff_angle"])
    assert abs(total - length) <= 2e-4 * length, (total, length)
    assert abs(_curve_length(s, SPOT["cutoff_angle"] + 0.1) - length) > 10 * 2e-4 * length
    r.close()


def test_the_spot_edge_distance_passes_warps_gradcheck():
    """spot_edge_distances' adjoints (the light, its axis, the receiver's corners, eye, center, up, fovy)
    against Warp's own finite differences, at points on the curve."""
    r, s, b = _frame(bare_spot_scene)
    geom, cam = r.geometry, s.camera
    first = np.arange(0, len(b.spot.edge), len(b.spot.edge) // 6)[:6]
    seg = b.spot.edge[first]
    corners = geom.points_np[geom.indices_np.reshape(-1, 3)[b.spots.face[seg]]]
    rows = np.concatenate([b.cones.at[b.spots.spot[seg]][:, None], b.cones.axis[b.spots.spot[seg]][:, None], corners],
                          axis=1)
    camera = np.tile(np.stack([geom.eye_offset(cam.eye), geom.eye_offset(cam.center), np.asarray(cam.up)]),
                     (len(first), 1))
    vec = lambda a: wp.array(np.asarray(a, np.float32).reshape(-1, 3), dtype=wp.vec3, requires_grad=True)  # noqa: E731
    inputs = [vec(rows), wp.array(b.cones.cos[b.spots.spot[seg]].astype(np.float32), dtype=float), vec(camera),
              wp.array(np.full(len(first), cam.fovy, np.float32), dtype=float, requires_grad=True), float(cam.near),
              cam.width, cam.height, wp.array(b.spot.at[first].astype(np.float32), dtype=wp.vec2)]
    out = wp.zeros(len(first), dtype=float, requires_grad=True)
    assert warp.autograd.gradcheck(spot_edge_distances, dim=len(first), inputs=inputs, outputs=[out], eps=1e-3,
                                   atol=2e-2, rtol=2e-2, show_summary=False, raise_exception=False)
    r.close()


def test_the_spot_cone_gradient_is_the_same_on_every_run_and_thread_count(weights):
    """The cone's sums run in a fixed order (each point its own adjoints, np.add.at on the host): two runs, and
    one thread against two, give the same gradient to the bit."""
    names = ["lights.0.position", "lights.0.direction", "objects.floor.vertices", "objects.occ.vertices",
             "camera.eye"]
    runs = [gradient(spot_scene, names, weights, True, threads=t) for t in (1, 1, 2)]
    for other in runs[1:]:
        for name in names:
            assert np.array_equal(runs[0][name], other[name]), name
