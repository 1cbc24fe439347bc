"""The boundary term of hard shadows' edges seen by camera rays (issue 38, backward(edges=True) with
render.shadows; image/grad_shadow_edges.py): the derivative of the box-filtered pixel integral in an occluder's
and a receiver's vertices, an occluder's pose, a point, spot or directional light, an area light's centre
(its soft shadow, a sum of its sample points' hard ones, and its own outline) and the camera, against central
differences of the forward at 128 x 128 samples a pixel (no pixel masked), each with the control that the
interior derivative alone (edges=False) is far off; the shadows' edges where the light's projection puts
them; the edge's speed against a float64 projection and Warp's gradcheck; a source's jump its own light's
alone; the sum the same to the bit on every run and thread count (what is still refused with shadows traced:
test_silhouette_edges.py's refusals, with and without shadows).
"""

from __future__ import annotations

import numpy as np
import pytest
import warp as wp
import warp.autograd

import warprt
from marks import exhaustive, slow
from oracle import image_point, line_distance, shadow_point
from warprt.image import EdgeFrame, EdgePoints, boundary, edge_sides, light_sides, shadow_speeds
from warprt.kernels import shadow_edge_distances
from warprt.scene import resolve_effects

from .converged import differences, gradient

WIDTH, HEIGHT = 24, 18
SPP = 256  # the gradient frame's: 16 x 16 strata (the differences': converged.FD_SPP)
TOL = 0.02  # measured: 0.01% to 1.5% of the differences (CASES' comments)
CONTROL = 0.3  # the interior derivative alone is off by more than this share of them (measured: 59% to 270%)
FLOOR = [[-2.5, 0.0, -2.0], [2.5, 0.0, -2.2], [2.4, 0.0, 2.3], [-2.6, 0.0, 2.1]]
TRIANGLE = [[-0.7, 0.9, -0.4], [0.8, 1.0, -0.2], [0.0, 1.1, 0.7]]
CAMERA = {"eye": [0.5, 4.0, 3.5], "center": [0.0, 0.2, 0.0], "width": WIDTH, "height": HEIGHT, "fovy": 45.0}
POINT = {"position": [1.0, 4.0, 1.5], "color": [0.9, 0.8, 0.7]}
DIRECTIONAL = {"type": "directional", "direction": [-0.3, -1.0, -0.4], "color": [0.9, 0.8, 0.7]}
SPOT = {"type": "spot", "position": [1.0, 4.0, 1.5], "target": [0.0, 0.0, 0.0], "cutoff_angle": 40.0,
        "beam_width": 20.0, "color": [3.0, 3.0, 3.0]}  # a ramp from 20 to 40 degrees: no hard cone
RECTANGLE = {"type": "area", "shape": "rectangle", "center": [0.6, 3.0, 0.8], "normal": [0.2, -1.0, 0.1],
             "size": [1.0, 0.8], "radiance": [4.0, 4.0, 3.5]}
SEEN_RECTANGLE = {"type": "area", "shape": "rectangle", "center": [-0.4, 2.4, -1.2], "normal": [0.1, -0.8, 0.6],
                  "size": [1.2, 0.6], "radiance": [3.0, 3.0, 2.5]}  # in view, its emitting side to the camera
OCCLUDERS = {
    "triangle": {"shape": "triangles", "vertices": TRIANGLE, "faces": [[0, 1, 2]]},
    # turned about each axis, so that no edge's image or shadow lies along the pixels' strata (a staircase of a
    # row of samples at once the differences would not resolve), no face's plane through the eye or a light
    "box": {"shape": "box", "size": [0.8, 0.6, 0.7], "rotate": [10.0, 30.0, 5.0], "translate": [0.1, 0.8, 0.0]},
    "aligned box": {"shape": "box", "size": [0.8, 0.6, 0.7], "translate": [0.17, 0.8, 0.06]},
    "ball": {"shape": "sphere", "subdivisions": 2, "smooth": True, "scale": 0.5, "translate": [0.1, 0.9, 0.0]},
}


def scene(spp: int = SPP, occluder: str = "triangle", lights=(POINT,), camera=None, materials=None, **render):
    """An occluder over a floor quad (two triangles), lit from above by ``lights``, seen from above and in
    front: its shadow on the floor in view, with shadows traced and one ray level. Diffuse only, so that no
    terminator's specular highlight jumps. ``materials``: the floor's and occluder's materials' other fields."""
    other = materials or {}
    return warprt.load_dict({
        "camera": camera or CAMERA,
        "render": {"ambient": [0.1] * 3, "max_depth": 1, "shadows": True, "spp": spp, "background": [0.1, 0.2, 0.3],
                   **render},
        "lights": list(lights),
        "materials": {"floor": {"kd": [0.6, 0.6, 0.5], "ks": [0.0] * 3, **other.get("floor", {})},
                      "occ": {"kd": [0.7, 0.2, 0.1], "ks": [0.0] * 3, **other.get("occ", {})}},
        "objects": [{"shape": "triangles", "name": "floor", "vertices": FLOOR, "faces": [[0, 2, 1], [0, 3, 2]],
                     "material": "floor"},
                    {"name": "occ", "material": "occ", **OCCLUDERS[occluder]}]})


def triangle_scene(spp: int = SPP):
    """A triangle's shadow under a point light."""
    return scene(spp)


def box_scene(spp: int = SPP):
    """A turned box's shadow under a point light: six silhouette edges from the light."""
    return scene(spp, "box")


def directional_scene(spp: int = SPP):
    return scene(spp, "box", [DIRECTIONAL])


def spot_scene(spp: int = SPP):
    return scene(spp, "triangle", [SPOT])


def ball_scene(spp: int = SPP):
    """A smooth ball (its normals following its vertices): where its faces turn from the light, its own
    shadow cuts its smooth shading, besides its shadow on the floor."""
    return scene(spp, "ball")


def area_scene(spp: int = SPP):
    """A turned box's soft shadow under a rectangle light out of view: 2 x 2 sample points, four hard shadows."""
    return scene(spp, "box", [RECTANGLE], light_samples=4)


def aligned_area_scene(spp: int = SPP):
    """An axis-aligned box under an axis-aligned rectangle light: each row of sample points lies in one plane
    with each of the box's edges along the rows, so their shadows' edges fall on one line."""
    return scene(spp, "aligned box", [{**RECTANGLE, "normal": [0.0, -1.0, 0.0]}], light_samples=4)


def seen_area_scene(spp: int = SPP):
    """A rectangle light in view, its outline against the background, and the box's soft shadow."""
    return scene(spp, "box", [SEEN_RECTANGLE], {"eye": [0.5, 2.2, 5.0], "center": [0.0, 1.0, 0.0],
                                                "width": WIDTH, "height": HEIGHT, "fovy": 50.0}, light_samples=4)


@pytest.fixture(scope="module")
def weights():
    """Of either sign, so that the smooth interior of a moving light's shading (the whole lit floor) and the
    shadow's edge weigh alike."""
    return (np.random.default_rng(11).random((HEIGHT, WIDTH, 3)) - 0.5).astype(np.float32)


def step(make, name: str, seed) -> np.ndarray:
    """A random direction for one parameter, of 0.3 a component (``seed`` a list: that direction)."""
    if not isinstance(seed, int):
        return np.asarray(seed, np.float64)
    r = warprt.Renderer(make())
    shape = np.shape(r.params[name])
    r.close()
    return np.random.default_rng(seed).standard_normal(shape) * 0.3


# (scene, name, seed or direction, step h, the differences' k: 64 k x 64 k samples a pixel); measured
# |edges=True - fd| / |fd| (and the interior's): 0.6% (95%), 0.5% (93%), 1.2% (70%), 0.9% (98%); 0.2% (94%),
# 0.1% (100%), 0.01% (100%); 0.1% (103%); 1.3% (269%); 1.5% (123%); 1.1% (68%), 0.4% (92%), 1.0% (91%);
# 0.4% (185%); 0.07% (99%); 1.7% (59%), 0.8% (90%)
CASES = [(triangle_scene, "objects.occ.vertices", 4, 4e-2, 2), (triangle_scene, "objects.floor.vertices", 6, 4e-2, 2),
         (triangle_scene, "lights.0.position", 5, 4e-2, 2), (triangle_scene, "camera.eye", 7, 4e-2, 2),
         (box_scene, "objects.occ.vertices", 8, 4e-2, 2), (box_scene, "objects.occ.translation", 18, 2e-2, 2),
         (box_scene, "objects.occ.rotation", 9, 2e-2, 2),
         # the sun tilted along z, its shadow sliding over the floor (a random tilt moves it less than the
         # differences resolve); a tenth of a pixel over [-h, h]
         (directional_scene, "lights.0.direction", [0.0, 0.0, 0.3], 1e-1, 2),
         (spot_scene, "lights.0.position", 11, 4e-2, 2), (ball_scene, "objects.occ.translation", 19, 2e-2, 2),
         (area_scene, "lights.0.center", 21, 4e-2, 2), (area_scene, "objects.occ.vertices", 13, 4e-2, 2),
         (area_scene, "objects.floor.vertices", 22, 4e-2, 2),  # its shadows' edges move with the receiver too
         (aligned_area_scene, "objects.occ.vertices", 14, 2e-2, 2),
         # the outline's slope needs 192 x 192 samples a pixel: at 128 x 128 the differences at h and h / 2
         # scatter by 3% about it (measured at 192: 0.68% off, 68 s on 2 quiet cores; at 256 x 256: 0.07%, 143 s
         # on a loaded run)
         (seen_area_scene, "lights.0.center", 15, 1e-2, 3),
         # a rectangle light's own shape: its size and normal move its points, its outline and its shadows' edges
         # (the normal tilted along z: a random tilt turns the four points' shadows less than the differences
         # resolve)
         (area_scene, "lights.0.normal", [0.0, 0.0, 0.3], 5e-2, 2), (seen_area_scene, "lights.0.size", 24, 1e-2, 4)]
QUICK = {0}  # the rest: slow (about 20 to 60 s each on 2 cores, the last 150 s)
# make test-exhaustive's alone (tests/marks.py): the receiver's vertices under an area light (the triangle's floor
# checks a receiver's) and the seen light's size (its centre checks its outline and its points' shadows moving):
# 75 s and 175 s of the suite's time; and, for the suite's 20 minutes on 2 cores, an area light's centre and its
# normal (the seen light's centre moves its points, its outline and their shadows) and the occluder under the
# aligned light (the area occluder's case checks the soft shadow; test_the_forwards_jump_is_its_sources_jumps_summed
# the aligned sources): 59 s, 49 s and 44 s
EXHAUSTIVE = {10, 12, 13, 15, 16}


@pytest.mark.parametrize("make, name, seed, h, k", [
    pytest.param(*case, id=f"{case[0].__name__}-{case[1]}-{case[2] if isinstance(case[2], int) else 'tilt'}",
                 marks=() if i in QUICK else (slow, exhaustive) if i in EXHAUSTIVE else slow)
    for i, case in enumerate(CASES)])
def test_the_shadow_edges_gradient_equals_central_differences(weights, make, name, seed, h, k):
    """edges=True against the differences of the converged forward, every pixel kept; the control: the
    interior derivative alone (edges=False) misses the moving shadows' term by far."""
    u = step(make, name, seed)
    fd = differences(make, name, u, weights, h=h, k=k)
    with_edges = float((gradient(make, [name], weights, True)[name] * u).sum())
    interior = float((gradient(make, [name], weights, False)[name] * u).sum())
    assert abs(with_edges - fd) <= TOL * abs(fd), (with_edges, fd)
    assert abs(interior - fd) > CONTROL * abs(fd), (interior, fd)


def _frame(make):
    """A rendered grad frame's Renderer, its scene's Boundary (the camera's edges and the shadows' points) and
    its effects."""
    s = make()
    r = warprt.Renderer(s)
    r.render(grad=True)
    fx = resolve_effects(s)
    return r, s, boundary(s, r.geometry, fx, r.geometry.eye_offset(s.camera.eye).astype(np.float64)), fx


@pytest.mark.parametrize("make", [triangle_scene, directional_scene], ids=["point", "directional"])
def test_a_shadows_edges_lie_where_the_light_projects_the_occluders(make):
    """Each shadow segment on the floor lies on the line the light projects its occluder edge to (central
    from a point light, parallel along a directional one: oracle.shadow_point), and an edge's segments add up
    to that projection's length (the shadow wholly on the floor; the floor's diagonal cuts some in two)."""
    r, s, b, _ = _frame(make)
    origin, light = r.geometry.origin, s.lights[0]
    directional = light.type == "directional"
    at = np.asarray(light.direction if directional else light.position, np.float64)
    seg = b.segments
    assert len(seg.face) >= 3 and set(seg.face) <= {0, 1}  # on the floor's two triangles only
    up = np.array([0.0, 1.0, 0.0])
    lengths = {}
    for e, q0, q1 in zip(map(tuple, seg.edge), seg.q0 + origin, seg.q1 + origin):
        v0, v1 = (r.geometry.points_np[i].astype(np.float64) + origin for i in e)
        a, c = (shadow_point(v, at, np.zeros(3), up, directional) for v in (v0, v1))
        for q in (q0, q1):
            assert np.linalg.norm(np.cross(c - a, q - a)) <= 1e-5 * np.linalg.norm(c - a) ** 2
        lengths.setdefault(frozenset(e), [np.linalg.norm(c - a), 0.0])[1] += np.linalg.norm(q1 - q0)
    assert len(lengths) == (3 if make is triangle_scene else 6)
    for expected, total in lengths.values():
        assert total == pytest.approx(expected, rel=1e-5)
    r.close()


def _oracle_distance(cam, x, v0, v1, light, p, directional):
    """The signed distance of image point x from the image of the shadow of the line v0 v1 on the plane of
    the triangle p (float64, oracle: the two ends' shadows projected)."""
    n = np.cross(p[1] - p[0], p[2] - p[0])
    a, c = (image_point(cam, shadow_point(v, light, p[0], n, directional)) for v in (v0, v1))
    return line_distance(x, a, c)


@pytest.mark.parametrize("make", [triangle_scene, directional_scene], ids=["point", "directional"])
def test_the_shadow_edge_speed_is_the_projections(make):
    """shadow_speeds (kernels.shadow_edge_distances on a wp.Tape, float32) against central differences in
    float64 of the signed distance of each point from the image of its edge's shadow (oracle: the edge's
    ends projected from the light onto the receiver's plane, then to the image), in every input: the occluder
    edge, the light, the receiver's corners and the eye (up to one sign per point: the oracle's line has no
    side). The control: the occluder edge's own image moves otherwise (a camera edge's speed is not a
    shadow's)."""
    r, s, b, _ = _frame(make)
    origin = r.geometry.origin
    pts, seg, src = b.shadows, b.segments, b.sources
    speed = shadow_speeds(s, r.geometry, src, seg, pts, "cpu")
    first = np.unique(pts.edge, return_index=True)[1]  # a point per segment
    faces = r.geometry.indices_np.reshape(-1, 3)
    world = lambda i: r.geometry.points_np[i].astype(np.float64) + origin  # noqa: E731
    for j in first:
        e = pts.edge[j]
        directional = bool(src.directional[seg.source[e]])
        inputs = {"v0": world(seg.edge[e, 0]), "v1": world(seg.edge[e, 1]),
                  "light": src.at[seg.source[e]] + (0.0 if directional else origin),
                  "p0": world(faces[seg.face[e], 0]), "p1": world(faces[seg.face[e], 1]),
                  "p2": world(faces[seg.face[e], 2]), "eye": np.asarray(s.camera.eye, np.float64)}

        def distance(key, k, h):
            moved = {n: v.copy() for n, v in inputs.items()}
            moved[key][k] += h
            cam = s.camera if key != "eye" else type(s.camera)(**{**vars(s.camera), "eye": tuple(moved["eye"])})
            return _oracle_distance(cam, pts.at[j], moved["v0"], moved["v1"], moved["light"],
                                    [moved["p0"], moved["p1"], moved["p2"]], directional)

        expected = np.array([[(distance(key, k, 1e-6) - distance(key, k, -1e-6)) / 2e-6 for k in range(3)]
                             for key in inputs])
        got = np.array([speed[key][j] for key in inputs])
        sign = np.sign(np.sum(got * expected))
        np.testing.assert_allclose(got, sign * expected, rtol=0, atol=1e-4 * np.abs(expected).max())  # measured: 3e-6
        own = np.array([(line_distance(pts.at[j], image_point(s.camera, inputs["v0"] + dv),
                                       image_point(s.camera, inputs["v1"])) -
                         line_distance(pts.at[j], image_point(s.camera, inputs["v0"] - dv),
                                       image_point(s.camera, inputs["v1"]))) / 2e-6 for dv in np.eye(3) * 1e-6])
        assert np.abs(np.abs(own) - np.abs(expected[0])).max() > 0.2 * np.abs(expected[0]).max()
    r.close()


def test_the_shadow_edge_distance_passes_warps_gradcheck():
    """shadow_edge_distances' adjoints (occluder edge, light, receiver, eye, center, up, fovy; point and
    directional lights) against Warp's own finite differences."""
    n = 6
    rng = np.random.default_rng(5)
    s = triangle_scene()
    cam = s.camera
    v = rng.uniform(-1, 1, (n, 2, 3)) * [1.0, 0.2, 1.0] + [0.0, 1.0, 0.0]
    light = np.where(np.arange(n)[:, None] % 2 == 0, rng.uniform(-1, 1, (n, 3)) + [0.0, 4.0, 0.0],
                     rng.uniform(-0.3, 0.3, (n, 3)) + [0.0, -1.0, 0.0])
    receiver = rng.uniform(-1, 1, (n, 3, 3)) * [2.0, 0.1, 2.0]
    geometry = np.concatenate([v, light[:, None], receiver], axis=1).reshape(-1, 3)
    camera = np.tile(np.stack([cam.eye, cam.center, cam.up]), (n, 1))
    at = rng.uniform(0, 1, (n, 2)) * [cam.width, cam.height]
    vec = lambda a: wp.array(np.asarray(a, np.float32), dtype=wp.vec3, requires_grad=True)  # noqa: E731
    inputs = [vec(geometry), wp.array((np.arange(n) % 2).astype(np.int32), dtype=int), vec(camera),
              wp.array(np.full(n, cam.fovy, np.float32), dtype=float, requires_grad=True), float(cam.near), cam.width,
              cam.height, wp.array(at.astype(np.float32), dtype=wp.vec2)]
    out = wp.zeros(n, dtype=float, requires_grad=True)
    assert warp.autograd.gradcheck(shadow_edge_distances, dim=n, inputs=inputs, outputs=[out], eps=1e-3, atol=2e-2,
                                   rtol=2e-2, show_summary=False, raise_exception=False)


def test_shadow_edges_hidden_behind_the_occluder_have_no_jump():
    """The box's shadow edges behind the box, seen from the camera: both rays either side meet the box, so
    its light's jump there is about 0, where the same shadow's visible edges on the floor jump by its light."""
    r, s, b, fx = _frame(box_scene)
    seen = warprt.Renderer(s, aovs=("object",)).render().aovs["object"].reshape(HEIGHT, WIDTH)
    jump = np.abs(light_sides(s, r.geometry, fx, b.sources, b.segments, b.shadows, "cpu")).max(axis=1)
    padded = np.pad(seen, 1, constant_values=-1)
    only = {k: np.ones_like(seen, bool) for k in (0, 1)}  # pixels whose 3 x 3 neighbourhood shows only object k
    for dy in range(3):
        for dx in range(3):
            for k in only:
                only[k] &= padded[dy:dy + HEIGHT, dx:dx + WIDTH] == k
    hidden, floor = only[1].reshape(-1)[b.shadows.pixel], only[0].reshape(-1)[b.shadows.pixel]
    assert hidden.sum() > 2 and floor.sum() > 2  # points: 1 a piece of an edge in a pixel
    assert jump[hidden].max() < 1e-3  # the box's own shading over 2e-3 of a pixel
    assert np.median(jump[floor]) > 0.05
    r.close()


def test_the_forwards_jump_is_its_sources_jumps_summed():
    """At each shadow point, the forward's own jump (edge_sides: the frame's walk either side) is the sum of
    every source's (light_sides: each sample point's light alone); under an edge along a row of the light's
    sample points the row's shadows' edges fall on one line, so there the forward's jump is the row's, not
    the one source's a segment stands for: the control, why each source's jump is its own."""
    r, s, b, fx = _frame(aligned_area_scene)
    pts, count = b.shadows, len(b.sources.at)
    n = len(pts.edge)
    full = edge_sides(s, r.geometry, EdgeFrame(fx, 0, 1), EdgePoints(None, np.arange(n), pts.at, pts.weight,
                                                                     pts.pixel, pts.normal[pts.edge]), "cpu")
    # every source at every point: segment rows s * n + i, of source s, at point i
    every = type(b.segments)(np.repeat(np.arange(count), n), *(np.zeros((count * n,) + x.shape[1:], x.dtype) for x in
                                                                (b.segments.edge[:1], b.segments.face[:1],
                                                                 b.segments.q0[:1], b.segments.q1[:1],
                                                                 b.segments.plane[:1])))
    tiled = EdgePoints(None, np.arange(count * n), np.tile(pts.at, (count, 1)), np.tile(pts.weight, count),
                       np.tile(pts.pixel, count), np.tile(pts.normal[pts.edge], (count, 1)))
    each = light_sides(s, r.geometry, fx, b.sources, every, tiled, "cpu").reshape(count, n, 3)
    np.testing.assert_allclose(each.sum(axis=0), full, atol=1e-5)
    own = each[b.segments.source[pts.edge], np.arange(n)]
    shared = np.abs(full - own).max(axis=1) > 0.3 * np.abs(full).max(axis=1)
    assert 0.1 < shared.mean() < 0.9
    r.close()


@pytest.mark.parametrize("make, names", [
    (area_scene, ["objects.occ.vertices", "objects.floor.vertices", "lights.0.center", "camera.eye", "camera.fovy"]),
    (directional_scene, ["objects.occ.vertices", "lights.0.direction", "camera.center"])], ids=["area", "directional"])
def test_the_shadow_edges_gradient_is_the_same_on_every_run_and_thread_count(weights, make, names):
    """The shadows' sums run in a fixed order (one launch a step, each point its own adjoints, np.add.at on
    the host): two runs, and one thread against two, give the same gradient to the bit."""
    runs = [gradient(make, names, weights, True, threads=t) for t in (1, 1, 2)]
    for other in runs[1:]:
        for name in names:
            assert np.array_equal(runs[0][name], other[name]), name
