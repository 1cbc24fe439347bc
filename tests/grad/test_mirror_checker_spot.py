"""The boundary term of a checker texture's squares and a hard spot's cone seen in planar mirrors (issue 38;
backward(edges=True), image/grad_mirror_edges.py: the checkers' lines and the cones' chords found from each
chain's virtual eye, unfolded): against central differences of the forward at 128 x 128 samples a pixel (no
pixel masked), in the checkered object's vertices and pose, the spot's position and direction, the camera and
the mirror's own pose, each with the controls that the interior derivative alone (edges=False) and the boundary
term without these edges' share in the mirror are far off.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import warprt
from marks import exhaustive, slow
from oracle import image_point, mirror_point
from oracle.camera import pinhole
from oracle.geometry import ray_plane
from warprt.image import MirroredSegments, boundary
from warprt.scene import resolve_effects

from .converged import differences, gradient, random_step

WIDTH, HEIGHT = 16, 12
SPP = 256  # the gradient frame's: 16 x 16 strata (the differences': converged.FD_SPP)
TOL = 0.02  # measured: CASES' comments
CONTROL = 0.3  # edges=False, and the k_r test's term without these edges' share in the mirror, are off by more than this
DROPPED = 0.15  # edges=True without that share is off the differences by more than this (measured: 21.6% at the
# least, the checker's translation, where the quad's silhouette in the mirror carries much of the term)
MIRROR = {"kd": [0.05] * 3, "ks": [0.0] * 3, "reflectivity": [0.8, 0.8, 0.8]}
WALL_MIRROR = [[-3.0, -2.5, 0.0], [3.2, -2.4, 0.0], [3.0, 2.6, 0.0], [-3.1, 2.5, 0.0]]
BEHIND = [[-3.0, -2.4, 3.0], [3.1, -2.6, 3.3], [3.0, 2.5, 3.1], [-2.9, 2.6, 2.8]]  # behind the camera, facing it
QUAD = [[0, 1, 2], [0, 2, 3]]


FLIP = np.array([1.0, 1.0, -1.0])  # the reflection across the mirror's plane, z = 0


def _scene(spp: int, lights: list, materials: dict, behind: dict, unfolded: bool):
    """The mirror and the quad behind the camera; ``unfolded``: instead the quad and the lights reflected across
    the mirror's plane and no mirror, one ray level: what the eye sees in the mirror, seen directly."""
    back = {"shape": "triangles", "name": "back", "vertices": BEHIND, "faces": QUAD, **behind}
    mirror = [{"shape": "triangles", "name": "mirror", "vertices": WALL_MIRROR, "faces": QUAD, "material": "mirror"}]
    if unfolded:
        back["vertices"], mirror = (np.asarray(BEHIND) * FLIP).tolist(), []
        lights = [{**light, **{k: (np.asarray(light[k]) * FLIP).tolist() for k in ("position", "target") if k in light}}
                  for light in lights]
    return warprt.load_dict({
        "camera": {"width": WIDTH, "height": HEIGHT, "eye": [0.3, 0.4, 2.0], "center": [0.0, 0.0, -1.0],
                   "fovy": 45.0},
        "render": {"ambient": [0.1] * 3, "max_depth": 1 if unfolded else 2, "shadows": False, "spp": spp,
                   "background": [0.1, 0.2, 0.3]},
        "lights": lights, "materials": {"mirror": MIRROR, **materials}, "objects": mirror + [back]})


def checker_scene(spp: int = SPP, unfolded: bool = False):
    """A wall mirror filling the frame; behind the camera, out of its view, a quad under a checker of scale
    (3.3, 2.7), lit from the mirror's side: its squares are seen in the mirror only."""
    return _scene(spp, [{"position": [0.5, 1.5, 1.0], "color": [0.9, 0.8, 0.7]}],
                  {"chk": {"kd_texture": {"checker": [[0.9, 0.8, 0.7], [0.1, 0.2, 0.3]], "scale": [3.3, 2.7],
                                          "offset": [0.1, 0.2]}, "ks": [0.0] * 3}},
                  {"uv": [[0, 0], [1, 0], [1, 1], [0, 1]], "material": "chk"}, unfolded)


def spot_scene(spp: int = SPP, unfolded: bool = False):
    """The same mirror; behind the camera a wall under a hard spot pointed at it: the cone's curve on the wall is
    seen in the mirror only."""
    return _scene(spp, [{"type": "spot", "position": [0.3, 0.5, 1.2], "target": [0.2, 0.1, 3.0],
                         "cutoff_angle": 35.0, "beam_width": 35.0, "color": [3.0, 3.0, 3.0]}],
                  {"wall": {"kd": [0.7, 0.7, 0.6], "ks": [0.0] * 3}}, {"material": "wall"}, unfolded)


def two_mirrors_spot_scene(spp: int = SPP):
    """A cone seen in a mirror seen in a mirror (three ray levels, test_mirror_edges.py's two mirrors): the floor
    mirror fills the frame, a tilted mirror above the camera turns its rays sideways to a wall, where a hard spot
    draws its cone: the curve is seen at the third level only."""
    floor = [[-3.0, 0.0, -3.0], [3.0, 0.0, -3.0], [3.0, 0.0, 3.0], [-3.0, 0.0, 3.0]]
    return warprt.load_dict({
        "camera": {"width": WIDTH, "height": HEIGHT, "eye": [0.2, 2.5, 0.3], "center": [0.0, 0.0, 0.0], "fovy": 30.0},
        "render": {"ambient": [0.1] * 3, "max_depth": 3, "shadows": False, "spp": spp, "background": [0.1, 0.2, 0.3]},
        "lights": [{"type": "spot", "position": [7.0, 6.0, 0.5], "target": [10.0, 6.5, 0.0], "cutoff_angle": 25.0,
                    "beam_width": 25.0, "color": [3.0, 3.0, 3.0]}],
        "materials": {"mirror": MIRROR, "wall": {"kd": [0.6, 0.6, 0.5], "ks": [0.0] * 3}},
        "objects": [{"shape": "triangles", "name": "floor", "vertices": floor, "faces": [[0, 2, 1], [0, 3, 2]],
                     "material": "mirror"},
                    {"shape": "triangles", "name": "tilted", "faces": QUAD, "material": "mirror",
                     "vertices": [[-2.5, 1.5, -4.0], [5.5, 9.5, -4.2], [5.6, 9.6, 4.0], [-2.5, 1.5, 4.1]]},
                    {"shape": "triangles", "name": "wall", "faces": QUAD, "material": "wall",
                     "vertices": [[10.0, -1.0, -6.0], [10.2, 13.0, -6.0], [10.0, 13.0, 6.0], [9.9, -1.0, 6.0]]}]})


SPOT = spot_scene().lights[0]


@pytest.fixture(scope="module")
def weights():
    """Of either sign, as test_mirror_edges.py's: the spot's smooth shading and its cone's edge weigh alike."""
    return (np.random.default_rng(11).random((HEIGHT, WIDTH, 3)) - 0.5).astype(np.float32)


@pytest.fixture(scope="module")
def positive():
    """Of one sign, as test_checker_edges.py's: with either sign the checker's loss is too small for the
    differences to settle (slopes 0.58 and 0.53 at h and h / 2)."""
    return np.random.default_rng(11).random((HEIGHT, WIDTH, 3)).astype(np.float32)


def _without_mirrored_lines(monkeypatch):
    """backward(edges=True) with the checkers' lines and the cones' chords seen in mirrors left out (their points
    dropped as the boundary keeps them): the control that these terms carry the difference."""
    take = MirroredSegments.take

    def dropped(self, parts):
        take(self, parts)
        self.checker_points = self.spot_points = None
    monkeypatch.setattr(MirroredSegments, "take", dropped)


# (scene, name, seed, step h, k x k images a pixel in the differences, the weights), each with its measured
# |edges=True - fd| / |fd| and edges=False's
CASES = [(spot_scene, "lights.0.direction", 5, 4e-2, 1, "weights"),  # 0.71% (100%)
         (spot_scene, "lights.0.position", 5, 4e-2, 2, "weights"),  # 0.81% (110%)
         (spot_scene, "objects.mirror.translation", 6, 2e-2, 2, "weights"),  # 0.26% (87%)
         (checker_scene, "objects.back.translation", 8, 4e-2, 3, "positive"),  # 0.48% (105%)
         # at h = 4e-2 3.8% off (the differences' slopes at h and h / 2 8% apart at 128 x 128: not settled)
         (checker_scene, "camera.eye", 7, 8e-2, 3, "positive"),  # 1.6% (54%)
         (two_mirrors_spot_scene, "lights.0.direction", 5, 4e-2, 2, "weights"),  # 0.57% (100%; 3.0% at k = 1)
         (two_mirrors_spot_scene, "lights.0.position", 5, 4e-2, 2, "weights")]  # 1.4% (104%)
QUICK = {0}  # the rest: make test-exhaustive's alone (30 to 60 s each on 2 shared cores)


@pytest.mark.parametrize("make, name, seed, h, k, w", [
    pytest.param(*case, id=f"{case[0].__name__}-{case[1]}", marks=() if i in QUICK else (slow, exhaustive))
    for i, case in enumerate(CASES)])
def test_the_mirrored_lines_gradient_equals_central_differences(request, monkeypatch, make, name, seed, h, k, w):
    """edges=True against the differences of the converged forward, every pixel kept; the controls: the interior
    derivative alone (edges=False), and edges=True without the checker's or the cone's term in the mirror, miss
    the moving reflection's term by far."""
    weights = request.getfixturevalue(w)
    u = random_step(make, name, seed)
    fd = differences(make, name, u, weights, h=h, k=k)
    along = lambda edges: float((gradient(make, [name], weights, edges)[name] * u).sum())  # noqa: E731
    with_edges, interior = along(True), along(False)
    _without_mirrored_lines(monkeypatch)
    dropped = along(True)
    assert abs(with_edges - fd) <= TOL * abs(fd), (with_edges, fd)
    assert abs(interior - fd) > CONTROL * abs(fd), (interior, fd)
    assert abs(dropped - fd) > DROPPED * abs(fd), (dropped, fd)


def _edge_terms(make, names, weights, **kw) -> dict:
    """backward(edges=True) less backward(edges=False) of one frame: the boundary term alone."""
    r = warprt.Renderer(make(16, **kw))
    r.render(grad=True)
    with_edges, interior = r.backward(weights, wrt=names, edges=True), r.backward(weights, wrt=names, edges=False)
    r.close()
    return {n: with_edges[n] - interior[n] for n in names}


@pytest.mark.parametrize("make, names", [
    (checker_scene, ["objects.back.vertices", "camera.eye"]),
    (spot_scene, ["lights.0.position", "lights.0.direction", "objects.back.vertices", "camera.eye"])],
    ids=["checker", "spot"])
def test_the_term_in_the_mirror_is_k_r_times_the_unfolded_scenes(weights, monkeypatch, make, names):
    """What the eye sees in the mirror is the scene reflected across its plane, dimmed by its k_r (0.8): the
    boundary term in the mirror equals k_r times that of the unfolded scene seen directly (its checker's and cone's
    terms test_checker_edges.py's and test_spot_edges.py's), each point parameter's reflected back (z negated);
    measured: within 9.4e-5 of the largest (the midpoint rule's
    error: pieces cut where the mirror's seams cross, not in the unfolded scene; 4e-6 with 2 Gauss points a piece). The control: without the checker's or the cone's term in the mirror
    (its silhouette's kept), far off."""
    direct = _edge_terms(make, names, weights, unfolded=True)
    expected = {n: 0.8 * (direct[n] if n == "camera.eye" else direct[n] * FLIP) for n in names}
    seen = _edge_terms(make, names, weights)
    for n in names:
        np.testing.assert_allclose(seen[n], expected[n], rtol=0, atol=2e-4 * np.abs(expected[n]).max(), err_msg=n)
    _without_mirrored_lines(monkeypatch)
    dropped = _edge_terms(make, names, weights)
    for n in names:
        assert np.abs(dropped[n] - expected[n]).max() > CONTROL * np.abs(expected[n]).max(), n


def test_the_mirrored_cone_points_lie_on_the_cone():
    """Each Gauss point of the cone's chords seen in the mirror, moved onto the curve (on_mirrored_cones), sees
    through the mirror (its camera ray reflected across the mirror's plane, float64) a point of the wall at the
    cutoff angle off the spot's axis; the control: its chords' midpoints lie off it."""
    s = spot_scene(1)
    r = warprt.Renderer(s)
    r.render(grad=True)
    geom = r.geometry
    b = boundary(s, geom, resolve_effects(s), geom.eye_offset(s.camera.eye).astype(np.float64))
    mb, origin = b.mirrored, geom.origin
    corners = geom.points_np.astype(np.float64)[geom.indices_np.reshape(-1, 3)] + origin
    cos = math.cos(math.radians(SPOT.cutoff_angle))
    axis = np.asarray(SPOT.direction, np.float64)

    def cosine(at, face):
        c = pinhole(s.camera)
        eye = mirror_point(c.eye, [0.0, 0.0, 0.0], [0.0, 0.0, 1.0])  # the mirror's plane: z = 0
        out = []
        for x, f in zip(at, face):
            d = -c.d_f * c.z_e + c.h * (x[1] / c.height - 0.5) * c.y_e + c.w * (x[0] / c.width - 0.5) * c.x_e
            d = d * [1.0, 1.0, -1.0]
            p = corners[f]
            y = eye + ray_plane(eye, d, p[0], np.cross(p[1] - p[0], p[2] - p[0])) * d
            to = y - np.asarray(SPOT.position, np.float64)
            out.append(to @ axis / np.linalg.norm(to))
        return np.asarray(out)

    pts = mb.spot_points
    assert len(pts.edge) > 50 and mb.spots.face.min() >= 2  # the wall's faces, after the mirror's
    assert np.abs(cosine(pts.at, mb.spots.face[pts.edge]) - cos).max() < 1e-7  # measured: 3.1e-8
    mid = np.stack([image_point(s.camera, q + origin) for q in 0.5 * (mb.spots.q0 + mb.spots.q1)])
    assert np.abs(cosine(mid, mb.spots.face) - cos).max() > 1e-6  # measured: 5.1e-6
    r.close()


@pytest.mark.parametrize("make, names", [
    (checker_scene, ["objects.back.vertices", "objects.mirror.vertices", "camera.eye"]),
    (spot_scene, ["lights.0.position", "lights.0.direction", "objects.mirror.vertices", "objects.back.vertices"])],
    ids=["checker", "spot"])
def test_the_mirrored_lines_gradient_is_the_same_on_every_run_and_thread_count(weights, make, names):
    """The mirrored lines' sums run in a fixed order (each point its own adjoints, np.add.at on the host): two
    runs, and one thread against two, give the same gradient to the bit."""
    runs = [gradient(lambda: make(16), names, weights, True, threads=t) for t in (1, 1, 2)]
    for other in runs[1:]:
        for name in names:
            assert np.array_equal(runs[0][name], other[name]), name
