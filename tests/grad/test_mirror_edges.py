"""The boundary term of the edges seen in planar mirrors (issue 38, backward(edges=True) with render.max_depth > 1;
image/grad_mirror_edges.py): the derivative of the box-filtered pixel integral in an object's vertices seen in a
mirror (its reflected silhouette), a point light's position (its shadow seen in a mirror), the camera, a mirror's
own vertices and pose, through one mirror and through a mirror seen in a mirror, against central differences of
the forward at 128 x 128 samples a pixel (no pixel masked), each with the control that the interior derivative
alone (edges=False) is far off; the mirrored edge's speed against a float64 reflection and projection and Warp's
gradcheck; a reflected edge off its mirror jumps by nothing; the sum the same to the bit on every run and thread
count; glass past MAX_GLASS_DEPTH (12) ray levels and more than MAX_CHAINS chains of mirrors still refused (a curved
mirror's edges are the crossings': test_curved_mirror_edges.py).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
import warp as wp
import warp.autograd

import warprt
from marks import exhaustive, slow
from oracle import image_point, line_distance, mirror_point, shadow_point
from warprt.image import (MAX_CHAINS, MAX_GLASS_DEPTH, EdgeFrame, boundary, chain_faces, edge_sides, mirrored_speeds,
                          shadow_rows)
from warprt.kernels import CONE, DIRECTIONAL_SHADOW, EDGE, POINT_SHADOW, make_mirrored_distances
from warprt.scene import resolve_effects

from .converged import check_against_differences, gradient

WIDTH, HEIGHT = 24, 18
SPP = 256  # the gradient frame's: 16 x 16 strata (the differences': converged.FD_SPP)
TOL = 0.02  # measured: 0.04% to 1.5% of the differences (CASES' comments)
CONTROL = 0.3  # the interior derivative alone is off by more than this share of them (measured: CASES' comments)
MIRROR = {"kd": [0.05] * 3, "ks": [0.0] * 3, "reflectivity": [0.8, 0.8, 0.8]}
DIFFUSE = {"ks": [0.0] * 3}
FLOOR = [[-6.0, 0.0, -6.0], [6.0, 0.0, -6.2], [6.1, 0.0, 6.0], [-6.0, 0.0, 6.1]]
QUAD = [[0, 2, 1], [0, 3, 2]]


def _scene(spp: int, max_depth: int, camera: dict, lights: list, materials: dict, objects: list, **render):
    return warprt.load_dict({
        "camera": {"width": WIDTH, "height": HEIGHT, **camera},
        "render": {"ambient": [0.1] * 3, "max_depth": max_depth, "shadows": True, "spp": spp,
                   "background": [0.1, 0.2, 0.3], **render},
        "lights": lights, "materials": materials, "objects": objects})


def floor_scene(spp: int = SPP):
    """A floor mirror filling the frame, seen from above; above the camera, out of its view, a triangle under a
    ceiling, lit from below: its silhouette against the ceiling and its shadow on it are seen in the mirror only."""
    return _scene(spp, 2, {"eye": [0.3, 2.0, 0.6], "center": [0.0, 0.0, 0.0], "fovy": 45.0},
                  [{"position": [1.5, 3.0, 1.0], "color": [0.9, 0.8, 0.7]}],
                  {"mirror": MIRROR, "ceiling": {"kd": [0.6, 0.6, 0.5], **DIFFUSE},
                   "occ": {"kd": [0.7, 0.2, 0.1], **DIFFUSE}},
                  [{"shape": "triangles", "name": "mirror", "vertices": FLOOR, "faces": QUAD, "material": "mirror"},
                   {"shape": "triangles", "name": "ceiling", "faces": [[0, 1, 2], [0, 2, 3]], "material": "ceiling",
                    "vertices": [[-6.0, 5.0, -6.0], [6.0, 5.2, -6.0], [6.0, 5.0, 6.0], [-6.0, 4.9, 6.0]]},
                   {"shape": "triangles", "name": "occ", "faces": [[0, 1, 2]], "material": "occ",
                    "vertices": [[-0.7, 3.9, -0.4], [0.8, 4.0, -0.2], [0.0, 4.1, 0.7]]}])


def wall_scene(spp: int = SPP):
    """A small mirror of two facets (not coplanar: two planar groups) on a wall, its outline in view, and a turned
    box beside it, seen directly and in the mirror, its reflection cut by the mirror's edge; a light between the
    box and the wall lights the side the mirror shows."""
    return _scene(spp, 2, {"eye": [-1.0, 1.0, 4.0], "center": [0.0, 0.0, 0.0], "fovy": 45.0},
                  [{"position": [2.0, 3.0, 4.0], "color": [0.8, 0.8, 0.7]},
                   {"position": [0.3, 1.2, -0.6], "color": [0.6, 0.6, 0.5]},
                   {"position": [-1.5, 2.0, 4.5], "color": [0.3, 0.4, 0.5]}],
                  {"crate": {"kd": [0.6, 0.3, 0.1], "ks": [0.4] * 3, "shininess": 30.0},
                   "wall": {"kd": [0.2, 0.5, 0.6], "ks": [0.1] * 3, "shininess": 8.0}, "mirror": MIRROR},
                  [{"shape": "box", "name": "crate", "size": [0.7, 0.6, 0.6], "rotate": [25.0, 35.0, 25.0],
                    "translate": [1.2, -0.3, 0.2], "material": "crate"},
                   {"shape": "triangles", "name": "back", "faces": [[0, 1, 2], [0, 2, 3]], "material": "wall",
                    "vertices": [[-1.6, -1.1, -1.5], [0.9, -1.2, -1.4], [1.0, 1.0, -1.6], [-1.4, 0.9, -1.5]]},
                   {"shape": "triangles", "name": "mirror", "faces": [[0, 1, 2], [0, 2, 3]], "material": "mirror",
                    "vertices": [[-1.0, -0.8, -1.3], [0.9, -0.85, -1.25], [0.85, 0.75, -1.35], [-0.95, 0.8, -1.4]]}],
                  shadows=False, ambient=[0.2] * 3)


def two_mirrors_scene(spp: int = SPP):
    """A mirror seen in a mirror (three ray levels): the floor mirror fills the frame, a tilted mirror above the
    camera fills the floor's reflection and turns its rays sideways, to a triangle and its shadow on a wall,
    seen at the third level only."""
    return _scene(spp, 3, {"eye": [0.2, 2.5, 0.3], "center": [0.0, 0.0, 0.0], "fovy": 30.0},
                  [{"position": [4.0, 6.0, 1.5], "color": [0.9, 0.8, 0.7]}],
                  {"mirror": MIRROR, "wall": {"kd": [0.6, 0.6, 0.5], **DIFFUSE}, "occ": {"kd": [0.7, 0.2, 0.1], **DIFFUSE}},
                  [{"shape": "triangles", "name": "floor", "vertices": FLOOR, "faces": QUAD, "material": "mirror"},
                   {"shape": "triangles", "name": "tilted", "faces": [[0, 1, 2], [0, 2, 3]], "material": "mirror",
                    "vertices": [[-2.5, 1.5, -4.0], [5.5, 9.5, -4.2], [5.6, 9.6, 4.0], [-2.5, 1.5, 4.1]]},
                   {"shape": "triangles", "name": "wall", "faces": [[0, 1, 2], [0, 2, 3]], "material": "wall",
                    "vertices": [[10.0, -1.0, -6.0], [10.2, 13.0, -6.0], [10.0, 13.0, 6.0], [9.9, -1.0, 6.0]]},
                   {"shape": "triangles", "name": "occ", "faces": [[0, 1, 2]], "material": "occ",
                    "vertices": [[7.0, 4.2, -0.5], [7.2, 5.8, 0.2], [6.8, 4.6, 0.9]]}])


@pytest.fixture(scope="module")
def weights():
    """Of either sign, as test_shadow_edges.py's (a light's smooth shading and the edges weigh alike)."""
    return (np.random.default_rng(11).random((HEIGHT, WIDTH, 3)) - 0.5).astype(np.float32)


def step(make, name: str, seed: int) -> np.ndarray:
    """A random direction for one parameter, of 0.3 a component."""
    r = warprt.Renderer(make())
    shape = np.shape(r.params[name])
    r.close()
    return np.random.default_rng(seed).standard_normal(shape) * 0.3


# (scene, name, seed, step h), each with its measured |edges=True - fd| / |fd| and the interior's (edges=False).
# The steps: the differences' own gate (h and h / 2 within 4%) is not enough where the image moves by a few of the
# differences' 128 strata a pixel over the step (the wall's camera.eye: slopes 0.180, 0.216, 0.239 at h = 4e-2,
# 2e-2, 1e-2, a staircase; 0.1789 at 8e-2 and 16e-2, and at 256 strata) or where the loss bends within the step
# (the wall mirror's translation: slopes -1.04, -1.47, -1.37, -1.34 at h = 8e-2 to 1e-2, at 128 and 256 strata).
CASES = [(floor_scene, "objects.occ.vertices", 4, 4e-2),  # 0.48% (interior 103%)
         (floor_scene, "lights.0.position", 5, 4e-2),  # 0.04% (85%)
         (floor_scene, "camera.eye", 7, 4e-2),  # 0.67% (132%)
         (floor_scene, "objects.mirror.translation", 6, 2e-2),  # 0.19% (110%)
         (wall_scene, "objects.crate.vertices", 4, 4e-2),  # 0.17% (73%)
         (wall_scene, "camera.eye", 7, 8e-2),  # 0.08% (80%)
         (wall_scene, "objects.mirror.vertices", 6, 4e-2),  # 0.23% (96%)
         (wall_scene, "objects.mirror.translation", 8, 1e-2),  # 0.36% (98%)
         (two_mirrors_scene, "objects.occ.vertices", 4, 4e-2),  # 0.15% (102%)
         (two_mirrors_scene, "lights.0.position", 5, 4e-2),  # 1.5% (106%)
         (two_mirrors_scene, "camera.eye", 7, 4e-2),  # 0.69% (100%)
         # a direction off the tilted mirror's plane: its translation within the plane moves nothing seen (the
         # gradient is along its normal), and seed 8's, 6 degrees off the plane, moved the loss less than the
         # differences resolve (-0.011: slopes -0.009 to -0.023 over the steps)
         (two_mirrors_scene, "objects.tilted.translation", 13, 2e-2)]  # unresolved (UNRESOLVED); interior 62%
# Cases whose differences do not settle at 128 strata a pixel: not a failure of the method measured yet, left in
# (xfail, not strict) until a finer reference decides them.
UNRESOLVED = {11: "edges 0.1394, interior 0.0528; the differences' slopes 0.086, 0.128, 0.124, 0.139, 0.148 at "
                  "h = 8e-2 to 5e-3 (128 strata a pixel) and 0.133 at h = 2e-2 with 256: a staircase at small steps "
                  "and a bend at large ones; 256 strata move them towards edges=True (4.5% off)"}
QUICK = {0}  # the rest: slow (about 2 minutes each on 2 cores)
# make test's: an occluder seen in a mirror (quick: its silhouette and its shadow seen in the mirror move), a
# mirror's own vertices; the rest exhaustive (make test-exhaustive), the light moving the shadow seen in a mirror and
# the occluder seen in a mirror seen in a mirror too, for the suite's 20 minutes on 2 cores (59 s and 77 s)
SUITE = {0, 6}


def _marks(i: int) -> tuple:
    marks = () if i in QUICK else (slow,) if i in SUITE else (slow, exhaustive)
    return marks + ((pytest.mark.xfail(reason=UNRESOLVED[i], strict=False),) if i in UNRESOLVED else ())


@pytest.mark.parametrize("make, name, seed, h", [
    pytest.param(*case, id=f"{case[0].__name__}-{case[1]}-{case[2]}", marks=_marks(i))
    for i, case in enumerate(CASES)])
def test_the_mirror_edges_gradient_equals_central_differences(weights, make, name, seed, h):
    """edges=True against the differences of the converged forward, every pixel kept; the control: the
    interior derivative alone (edges=False) misses the moving reflections' term by far."""
    check_against_differences(make, name, step(make, name, seed), weights, h, TOL, CONTROL)


def _frame(make):
    """A frame of ``make`` (one sample a pixel) and its Boundary, seen from its eye."""
    s = make(1)
    r = warprt.Renderer(s)
    r.render(grad=True)
    fx = resolve_effects(s)
    return r, s, boundary(s, r.geometry, fx, r.geometry.eye_offset(s.camera.eye).astype(np.float64)), fx


def _unfolded(q, mirrors) -> np.ndarray:
    """The point q as the eye sees it through the mirror faces ``mirrors`` (its ray's first first): reflected
    across the last one's plane, then each before it (oracle.mirror_point)."""
    for m in mirrors[::-1]:
        q = mirror_point(q, m[0], np.cross(m[1] - m[0], m[2] - m[0]))
    return q


def _oracle_distance(cam, x, inputs: dict, level: int, shadow: bool, directional: bool) -> float:
    """The signed distance of image point x from the image of an edge v0 v1 (with ``shadow``: its shadow from
    the light on the plane of the receiver p0 p1 p2, oracle.shadow_point) seen through ``level`` mirror faces
    m<i><c>, in float64."""
    ends = [inputs["v0"], inputs["v1"]]
    if shadow:
        n = np.cross(inputs["p1"] - inputs["p0"], inputs["p2"] - inputs["p0"])
        ends = [shadow_point(v, inputs["light"], inputs["p0"], n, directional) for v in ends]
    mirrors = [[inputs[f"m{i}{c}"] for c in range(3)] for i in range(level)]
    return line_distance(x, *(image_point(cam, _unfolded(q, mirrors)) for q in ends))


def _speed_cases(r, s, b, fx):
    """(points, speeds, per point its inputs' keys and float64 world values, level, whether a shadow's and
    directional) of the mirrored edges and shadows' edges of a frame (b.mirrored), a point per segment whose
    ray follows its chain."""
    geom, mb, origin = r.geometry, b.mirrored, r.geometry.origin
    p = geom.points_np.astype(np.float64) + origin
    faces = geom.indices_np.reshape(-1, 3)
    out = []
    for pts, chain, shadow in ((mb.camera, mb.edge_chain, False), (mb.shadow_points, mb.shadow_chain, True)):
        cf = chain_faces(s, geom, fx, mb.group, mb.chains, chain, pts, "cpu")
        if shadow:
            seg, src = mb.shadows, b.sources
            rows = shadow_rows(geom, src, seg, pts)
            kind = np.where(src.directional[seg.source[pts.edge]], DIRECTIONAL_SHADOW, POINT_SHADOW)
        else:
            rows = np.zeros((len(pts.edge), 6, 3))
            rows[:, :2] = geom.points_np.astype(np.float64)[mb.edges[pts.edge]]
            kind = np.full(len(pts.edge), EDGE)
        speed = mirrored_speeds(s, geom, rows, kind, cf, pts, "cpu")
        first = np.unique(pts.edge, return_index=True)[1]
        for j in first[cf.follows[first]]:
            directional = bool(kind[j] == DIRECTIONAL_SHADOW)
            keys = ("v0", "v1", "light", "p0", "p1", "p2") if shadow else ("v0", "v1")
            inputs = {k: rows[j, i] + (0.0 if k == "light" and directional else origin) for i, k in enumerate(keys)}
            inputs.update({f"m{i}{c}": p[faces[cf.faces[j, i], c]] for i in range(cf.level[j]) for c in range(3)})
            inputs["eye"] = np.asarray(s.camera.eye, np.float64)
            out.append((pts.at[j], {k: speed[k][j] for k in inputs}, inputs, int(cf.level[j]), shadow, directional))
    return out


@pytest.mark.parametrize("make", [floor_scene, two_mirrors_scene], ids=["one mirror", "two mirrors"])
def test_the_mirrored_edge_speed_is_the_reflections_projection(make):
    """mirrored_speeds (kernels.make_mirrored_distances on a wp.Tape, float32) against central differences in
    float64 of the signed distance of each point from its edge's (or its shadow's edge's) image through its
    mirrors (oracle: the ends, or their shadows, reflected across each mirror face's plane, the last first,
    then projected), in every input: the edge, the light, the receiver, each mirror face's corners and the eye
    (up to one sign per point: the oracle's line has no side). The control: the edge's own image, unreflected,
    moves otherwise."""
    r, s, b, fx = _frame(make)
    cases = _speed_cases(r, s, b, fx)
    assert {(level, shadow) for *_, level, shadow, _ in cases} >= (
        {(1, False), (1, True)} if make is floor_scene else {(2, True)})
    for x, got, inputs, level, shadow, directional in cases:
        def distance(key, k, h):
            moved = {n: v.copy() for n, v in inputs.items()}
            moved[key][k] += h
            cam = s.camera if key != "eye" else type(s.camera)(**{**vars(s.camera), "eye": tuple(moved["eye"])})
            return _oracle_distance(cam, x, moved, level, shadow, directional)

        expected = np.array([[(distance(key, k, 1e-6) - distance(key, k, -1e-6)) / 2e-6 for k in range(3)]
                             for key in inputs])
        found = np.array([got[key] for key in inputs])
        sign = np.sign(np.sum(found * expected))
        np.testing.assert_allclose(found, sign * expected, rtol=0, atol=1e-4 * np.abs(expected).max())  # measured: 2e-6
        if not shadow:
            own = [_oracle_distance(s.camera, x, {**inputs, "v0": inputs["v0"] + dv}, 0, False, False)
                   - _oracle_distance(s.camera, x, {**inputs, "v0": inputs["v0"] - dv}, 0, False, False)
                   for dv in np.eye(3) * 1e-6]
            assert np.abs(np.abs(np.array(own) / 2e-6) - np.abs(expected[0])).max() > 0.2 * np.abs(expected[0]).max()
    r.close()


def _on_cone(cam, axis, light, receiver, mirrors, cos: float) -> np.ndarray:
    """An image point of the curve where the cone (light, axis, cos) meets the receiver's plane, all seen through
    the mirror faces ``mirrors`` (unfolded, float64): the first of its rays that meets the plane in front of the
    eye."""
    apex, tip = _unfolded(light, mirrors), _unfolded(light + axis, mirrors)
    p = np.stack([_unfolded(q, mirrors) for q in receiver])
    u = (tip - apex) / np.linalg.norm(tip - apex)
    a = np.cross(u, [1.0, 0.0, 0.0])
    a /= np.linalg.norm(a)
    normal = np.cross(p[1] - p[0], p[2] - p[0])
    for phi in np.linspace(0.0, 2.0 * np.pi, 64, endpoint=False):
        ray = cos * u + np.sqrt(1.0 - cos * cos) * (np.cos(phi) * a + np.sin(phi) * np.cross(u, a))
        t = ((p[0] - apex) @ normal) / (ray @ normal)
        y = apex + t * ray
        if t > 0.0 and (y - np.asarray(cam.eye)) @ (np.asarray(cam.center) - np.asarray(cam.eye)) > 0.0:
            return image_point(cam, y)
    raise AssertionError("no ray of the cone meets the receiver in front of the eye")


def test_the_mirrored_distance_passes_warps_gradcheck():
    """make_mirrored_distances' adjoints (edge, light, receiver, the mirror faces, eye, center, up, fovy; mesh
    edges, point and directional shadows, a spot's cone, through one mirror and two) against Warp's own finite
    differences."""
    n, levels = 8, 2
    rng = np.random.default_rng(5)
    cam = floor_scene(1).camera
    v = rng.uniform(-1, 1, (n, 2, 3)) * [1.0, 0.2, 1.0] + [0.0, 4.0, 0.0]
    kind = np.arange(n) % 4
    light = np.where(kind[:, None] == 2, rng.uniform(-0.3, 0.3, (n, 3)) + [0.0, 1.0, 0.0],
                     rng.uniform(-1, 1, (n, 3)))
    axis = rng.uniform(-0.2, 0.2, (n, 3)) + [0.0, 1.0, 0.0]  # a cone's (CONE: v0), towards the receiver
    v[:, 0] = np.where(kind[:, None] == 3, axis / np.linalg.norm(axis, axis=1, keepdims=True), v[:, 0])
    receiver = rng.uniform(-1, 1, (n, 3, 3)) * [2.0, 0.1, 2.0] + [0.0, 5.0, 0.0]
    floor = np.array([[-3.0, 0.0, -3.0], [0.0, 0.0, 3.0], [3.0, 0.0, -3.0]])
    tilted = np.array([[-2.5, 1.5, -4.0], [5.5, 9.5, -4.2], [5.6, 9.6, 4.0]])
    mirrors = np.stack([floor, tilted])[None] + rng.uniform(-0.1, 0.1, (n, levels, 3, 3))
    geometry = np.concatenate([v, light[:, None], receiver], axis=1).reshape(-1, 3)
    camera = np.tile(np.stack([cam.eye, cam.center, cam.up]), (n, 1))
    at = rng.uniform(0, 1, (n, 2)) * [cam.width, cam.height]
    level = 1 + np.arange(n) // 4 % 2
    for j in np.flatnonzero(kind == 3):  # a cone's points on its curve (far off it, float32's differences are noise)
        at[j] = _on_cone(cam, v[j, 0], light[j], receiver[j], mirrors[j, :level[j]], 0.9)
    vec = lambda a: wp.array(np.asarray(a, np.float32).reshape(-1, 3), dtype=wp.vec3, requires_grad=True)  # noqa: E731
    ints = lambda a: wp.array(np.asarray(a, np.int32), dtype=int)  # noqa: E731
    cos = wp.array(np.full(n, 0.9, np.float32), dtype=float)
    inputs = [vec(geometry), vec(mirrors), ints(kind), ints(level), cos, vec(camera),
              wp.array(np.full(n, cam.fovy, np.float32), dtype=float, requires_grad=True), float(cam.near), cam.width,
              cam.height, wp.array(at.astype(np.float32), dtype=wp.vec2)]
    out = wp.zeros(n, dtype=float, requires_grad=True)
    assert [EDGE, POINT_SHADOW, DIRECTIONAL_SHADOW, CONE] == [0, 1, 2, 3]
    assert warp.autograd.gradcheck(make_mirrored_distances(levels), dim=n, inputs=inputs, outputs=[out], eps=1e-3,
                                   atol=2e-2, rtol=2e-2, show_summary=False, raise_exception=False)


def test_a_reflection_off_its_mirror_jumps_by_nothing():
    """The crate's reflection in the small wall mirror is cut by the mirror's outline: where the unfolded
    edges run on past it (pixels with no mirror in their 3 x 3 neighbourhood) their rays miss the mirror
    (chain_faces: not following their chain, so no term) and the forward's jump there is 0, where inside the
    mirror (its pixels alone) the rays of some follow and the reflected silhouette jumps."""
    r, s, b, fx = _frame(wall_scene)
    pts, mb = b.mirrored.camera, b.mirrored
    seen = warprt.Renderer(s, aovs=("object",)).render().aovs["object"].reshape(HEIGHT, WIDTH)
    jump = np.abs(edge_sides(s, r.geometry, EdgeFrame(fx, 0, s.render.max_depth), pts, "cpu")).max(axis=1)
    follows = chain_faces(s, r.geometry, fx, mb.group, mb.chains, mb.edge_chain, pts, "cpu").follows
    padded = np.pad(seen, 1, constant_values=-1)
    near, inside = np.zeros_like(seen, bool), np.ones_like(seen, bool)  # the mirror (object 2) near, all round
    for dy in range(3):
        for dx in range(3):
            near |= padded[dy:dy + HEIGHT, dx:dx + WIDTH] == 2
            inside &= padded[dy:dy + HEIGHT, dx:dx + WIDTH] == 2
    away, inside = ~near.reshape(-1)[pts.pixel], inside.reshape(-1)[pts.pixel]
    assert away.sum() > 8 and not follows[away].any() and jump[away].max() < 1e-6
    assert (inside & follows).sum() > 8 and jump[inside & follows].max() > 0.1
    r.close()


def test_the_mirror_edges_gradient_is_the_same_on_every_run_and_thread_count(weights):
    """The mirrors' sums run in a fixed order (each point its own adjoints, np.add.at on the host): two runs,
    and one thread against two, give the same gradient to the bit."""
    names = ["objects.occ.vertices", "objects.mirror.vertices", "lights.0.position", "camera.eye"]
    runs = [gradient(lambda: floor_scene(16), names, weights, True, threads=t) for t in (1, 1, 2)]
    for other in runs[1:]:
        for name in names:
            assert np.array_equal(runs[0][name], other[name]), name


def _box_of_mirrors(spp: int):
    """The camera inside a box whose six faces are mirrors (planar: six groups), four ray levels: more chains
    of mirrors than followed."""
    return _scene(spp, 4, {"eye": [0.2, 0.1, 0.3], "center": [1.0, 0.3, -2.0], "fovy": 60.0},
                  [{"position": [-0.3, 0.5, 0.2], "color": [0.9, 0.8, 0.7]}], {"mirror": MIRROR},
                  [{"shape": "box", "name": "room", "size": [3.0, 2.5, 3.5], "material": "mirror"},
                   {"shape": "triangles", "name": "occ", "faces": [[0, 1, 2]], "material": "mirror",
                    "vertices": [[-0.7, 0.9, -0.4], [0.8, 1.0, -0.2], [0.0, 1.1, 0.7]]}])


def _glass_floor(spp: int):
    """floor_scene with its mirror glass, traced to more ray levels than the edges seen through glass cover
    (MAX_GLASS_DEPTH, 12: to 8 they are, test_glass_edges.py)."""
    s = floor_scene(spp)
    glass = replace(s.materials["mirror"], ior=1.5, transmittance=(0.9,) * 3, reflectivity=(0.0,) * 3)
    return replace(s, materials={**s.materials, "mirror": glass},
                   render=replace(s.render, max_depth=MAX_GLASS_DEPTH + 1))


@pytest.mark.parametrize("make, why", [(_glass_floor, "glass"),
                                       (_box_of_mirrors, f"more than {MAX_CHAINS} chains")],
                         ids=["glass", "too many chains"])
def test_what_mirror_edges_leave_out_is_refused_in_one_line(weights, make, why):
    """Glass's rays past MAX_GLASS_DEPTH levels and more chains of mirrors than MAX_CHAINS: one line naming
    ``edges`` and why; a colour is not refused, and edges=False never is."""
    r = warprt.Renderer(make(1))
    r.render(grad=True)
    with pytest.raises(warprt.SceneError, match="edges") as e:
        r.backward(weights, wrt=["objects.occ.vertices"], edges=True)
    assert why in str(e.value) and "\n" not in str(e.value)
    r.backward(weights, wrt=["materials.mirror.kd"], edges=True)
    r.backward(weights, wrt=["objects.occ.vertices"], edges=False)
    r.close()
