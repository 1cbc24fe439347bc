"""The boundary term of the edges seen through glass (issue 38, backward(edges=True) with refraction;
image/grad_glass_edges.py): a deterministic screen-space crossing estimator. Checked:

- on a scene without glass, the crossings of every node (the camera's own silhouettes included) agree with the
  camera edges' term of image/grad_edges.py, an independent method (edges enumerated and integrated at Gauss
  points), within the crossings' quadrature error; each set of lines alone (horizontal or vertical) is far off;
  and the crossings below a dielectric are none there (nothing the other terms count is counted again);
- the derivative in an occluder's vertices (its silhouette and its shadow seen through the glass) and a point
  light's position (the occluder's shadow), seen through a flat glass slab and a smooth glass ball, against central differences of the forward at 64 x 64 samples a pixel
  (tests/grad/converged.py, no pixel masked), each with the control that the interior derivative alone
  (edges=False) is far off;
- the camera's boundary term through the slab found two ways (the camera edges' term plus the crossings below
  the split, and the crossings at every node) the same: the glass's outline counted once;
- the camera's eye through the slab and the smooth glass ball, along each axis, against the same differences
  (make test-exhaustive's), with the same control;
- the glass's ior (it bends what is seen through it: the crossings' speed in each refraction's eta) through the slab
  (make test's) and the smooth ball (make test-exhaustive's) against the same differences, with the same control;
- the occluder's vertices seen through a glass light pipe at 8 ray levels (past the 6 once refused) against the
  same differences, with the same control, and the gradient traced to 6 levels further from it than the tolerance
  (make test-exhaustive's); scenes/glass_slab.toml (8 levels) at 4 x 2 pixels runs, the same on two runs;
- the glass's own vertices, translation and rotation (its outline, its creases seen through it, what it bends and
  its shadow moving at once), the flat slab's and the smooth ball's (whose vertex normals turn its rays), against
  the same differences, with the same control; the smooth ball's term linear in the image adjoint, on a second
  backward too;
- the sum the same to the bit on every run and thread count;
- a checker's squares (the signatures' squares, their lines' boundary function): without glass the crossings of
  every node agree with the direct checker lines' term (image/grad_checker_edges.py), and seen through the slab
  the wall's vertices and the camera's eye against the same differences, with the same control;
- what the crossings do not cover, more than MAX_GLASS_DEPTH ray levels, refused in one line naming ``edges``:
  test_mirror_edges.py (a hard spot's cone seen through glass is covered: test_glass_spot_edges.py; area lights'
  soft shadows too: test_glass_area_edges.py).
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

import warprt
from marks import exhaustive, slow
from warprt.image import EdgeFrame, glass_crossings, glass_terms
from warprt.kernels import stack_size
from warprt.scene import Texture, resolve_effects

from .converged import check_against_differences, gradient
from .test_checker_edges import quad_scene
from .test_mirror_edges import step

WIDTH, HEIGHT = 24, 18
SPP = 256
TOL = 0.03  # measured: CASES' comments
CONTROL = 0.3
GLASS = {"ior": 1.5, "ka": [0, 0, 0], "kd": [0, 0, 0], "ks": [0.0] * 3, "transmittance": [0.9, 0.9, 0.9]}
DIFFUSE = {"ks": [0.0] * 3}
ROOT = Path(__file__).resolve().parents[2]
WALL = [[-4, -3, -1.0], [4, -3, -1.1], [4, 3, -1.0], [-4, 3, -0.9]]


def _scene(spp: int, max_depth: int, camera: dict, light: list, glass: dict, occ: list):
    return warprt.load_dict({
        "camera": {"width": WIDTH, "height": HEIGHT, "center": [0.0, 0.0, 0.0], **camera},
        "render": {"ambient": [0.2] * 3, "max_depth": max_depth, "shadows": True, "spp": spp,
                   "background": [0.1, 0.2, 0.3]},
        "lights": [{"position": light, "color": [0.8, 0.8, 0.7]}],
        "materials": {"glass": GLASS, "occ": {"kd": [0.7, 0.2, 0.1], **DIFFUSE},
                      "wall": {"kd": [0.3, 0.6, 0.5], **DIFFUSE}},
        "objects": [{**glass, "material": "glass"},
                    {"shape": "triangles", "name": "occ", "faces": [[0, 1, 2]], "material": "occ", "vertices": occ},
                    {"shape": "triangles", "name": "wall", "faces": [[0, 1, 2], [0, 2, 3]], "material": "wall",
                     "vertices": WALL}]})


def slab_scene(spp: int = SPP):
    """A turned flat glass slab filling most of the view, a triangle behind it and the triangle's shadow on a
    wall, both seen through the slab (in, out: three ray levels), where the slab's own shadow and total internal
    reflection at its side also cut the view."""
    return _scene(spp, 3, {"eye": [0.3, 0.4, 4.0], "fovy": 40.0}, [1.0, 2.5, 3.0],
                  {"shape": "box", "name": "slab", "size": [2.0, 1.6, 0.5], "rotate": [10.0, 35.0, 5.0],
                   "translate": [-0.3, 0.0, 1.6]},
                  [[-0.6, -0.4, 0.0], [0.5, -0.3, 0.1], [-0.1, 0.6, -0.1]])


def ball_scene(spp: int = SPP):
    """A smooth glass ball (an icosphere, interpolated normals) in front of a triangle and its shadow on a
    wall: the triangle seen upside down through it, four ray levels."""
    return _scene(spp, 4, {"eye": [0.2, 0.3, 4.0], "fovy": 30.0}, [1.5, 2.0, 3.0],
                  {"shape": "sphere", "name": "ball", "radius": 0.7, "subdivisions": 3, "smooth": True,
                   "translate": [0.0, 0.0, 1.2]},
                  [[-0.5, -0.4, 0.0], [0.6, -0.2, 0.1], [-0.1, 0.5, -0.1]])


def pipe_scene(spp: int = SPP, max_depth: int = 8):
    """A glass light pipe, a long thin bar seen end on from close by, in front of the triangle and its shadow on
    the wall: a ray through its front face meets its sides at past the critical angle, a ray level each total
    internal reflection, so the triangle is seen as in a kaleidoscope at every level from 5 on (points seeing it
    deepest at levels 5 to 8 on a 4 x 4 grid a pixel: 20, 90, 435, 386; deeper ones too). Traced to 8 levels: past
    the 6 the edges seen through glass once stopped at (issue 38)."""
    return _scene(spp, max_depth, {"eye": [0.1, 0.05, 4.0], "fovy": 60.0}, [1.0, 2.5, 3.0],
                  {"shape": "box", "name": "pipe", "size": [0.5, 0.4, 3.0], "translate": [0.0, 0.0, 2.0]},
                  [[-0.6, -0.4, 0.0], [0.5, -0.3, 0.1], [-0.1, 0.6, -0.1]])


def triangle_scene(spp: int = SPP):
    """No glass: a flat-shaded triangle against the background (test_silhouette_edges.py's)."""
    return warprt.load_dict({
        "camera": {"eye": [0.0, 0.0, 4.0], "center": [0.0, 0.0, 0.0], "width": WIDTH, "height": HEIGHT, "fovy": 40.0},
        "render": {"ambient": [0.2] * 3, "max_depth": 1, "shadows": False, "spp": spp, "background": [0.1, 0.2, 0.3]},
        "lights": [{"position": [2.0, 3.0, 4.0], "color": [0.9, 0.8, 0.7]}],
        "materials": {"red": {"kd": [0.7, 0.2, 0.1], "ks": [0.3] * 3, "shininess": 20.0}},
        "objects": [{"shape": "triangles", "name": "tri", "faces": [[0, 1, 2]], "material": "red",
                     "vertices": [[-1.1, -0.8, 0.0], [1.2, -0.5, 0.2], [0.1, 1.0, -0.1]]}]})


@pytest.fixture(scope="module")
def weights():
    return (np.random.default_rng(11).random((HEIGHT, WIDTH, 3)) - 0.5).astype(np.float32)


def frame_crossings(s, r, through: bool = True, **bits) -> list:
    """glass_crossings of a grad frame ``r`` of ``s`` (``bits``: EdgeFrame's cone_bits, square_bits, hidden_bits)."""
    fx = resolve_effects(s)
    frame = EdgeFrame(fx, stack_size(s.render.max_depth) if fx.refraction else 0, s.render.max_depth, **bits)
    return glass_crossings(s, r.geometry, frame, "cpu", through)


def _crossing_terms(s, r, weights, through: bool, square_bits: bool = True) -> list:
    """The BoundaryTerms of the crossings of a grad frame ``r`` of ``s``, one per set of lines
    (EdgeFrame.square_bits: ``square_bits``)."""
    return glass_terms(frame_crossings(s, r, through, square_bits=square_bits),
                       weights.reshape(-1, 3).astype(np.float64), len(r.geometry.points_np))


def test_the_crossings_agree_with_the_camera_edges_term(weights):
    """Without glass, every crossing counted (through=False): the crossings' term in the triangle's vertices and
    the camera's eye is the camera edges' term (edges=True less edges=False), within the lines' quadrature
    (measured: 2.5% of the largest vertex component, 1.2% of the eye's); the horizontal or the vertical lines
    alone carry only their share (> 30% off); and no crossing lies below a dielectric: with through=True, none."""
    s = triangle_scene(1)
    r = warprt.Renderer(s)
    r.render(grad=True)
    names = ["objects.tri.vertices", "camera.eye"]
    edges, interior = r.backward(weights, wrt=names, edges=True), r.backward(weights, wrt=names, edges=False)
    want = {n: edges[n] - interior[n] for n in names}
    terms = _crossing_terms(s, r, weights, False)
    got = {"objects.tri.vertices": sum(t.points for t in terms), "camera.eye": sum(t.camera["eye"] for t in terms)}
    for name in names:
        scale = np.abs(want[name]).max()
        assert np.abs(got[name] - want[name]).max() <= 0.04 * scale, (name, got[name], want[name])
    for t in terms:
        assert np.abs(t.points - want["objects.tri.vertices"]).max() > 0.3 * np.abs(want["objects.tri.vertices"]).max()
    assert _crossing_terms(s, r, weights, True) == []
    r.close()


# (scene, name, seed, step h), each with its measured |edges=True - fd| / |fd| and the interior's (edges=False); the
# differences at 64 x 64 strata a pixel (k = 1: a glass frame at 128 x 128 costs 4 times as much, minutes a step).
CASES = [(slab_scene, "objects.occ.vertices", 4, 2e-2),  # 0.47% (interior 135%)
         (ball_scene, "objects.occ.vertices", 4, 2e-2),  # 1.2% (interior 186%)
         # its shadow seen through the slab, and the wall's light (at 2e-2 the differences' h and h / 2 part by 4.5%)
         (slab_scene, "lights.0.position", 5, 4e-2),  # 1.8% (interior 492%)
         (ball_scene, "lights.0.position", 5, 2e-2)]  # 0.19% (interior 113%)
SUITE = {0}  # make test's: an occluder seen through the slab; the ball's exhaustive (make test-exhaustive)


@pytest.fixture(scope="module")
def positive():
    """Weights of one sign: with either sign, the loss's derivative along a direction is a few per cent of what
    its pixels add, and the crossings' per-pixel quadrature error (1% to 3%) would be amplified in it."""
    return np.random.default_rng(11).random((HEIGHT, WIDTH, 3)).astype(np.float32)


@pytest.mark.parametrize("make, name, seed, h", [
    pytest.param(*case, id=f"{case[0].__name__}-{case[1]}-{case[2]}",
                 marks=(slow,) if i in SUITE else (slow, exhaustive)) for i, case in enumerate(CASES)])
def test_the_glass_edges_gradient_equals_central_differences(positive, make, name, seed, h):
    """edges=True against the differences of the converged forward, every pixel kept; the control: the
    interior derivative alone (edges=False) misses the term of what moves behind the glass by far."""
    check_against_differences(make, name, step(make, name, seed), positive, h, TOL, CONTROL, k=1)


@slow
@exhaustive
def test_the_glass_edges_past_six_levels_equal_central_differences(positive):
    """The occluder's vertices seen through the light pipe at 8 ray levels against the differences of the
    converged forward (measured: 13.097 against 13.043, 0.41%; the interior alone 21.75, 66.7% off; minutes, most
    of them the differences': make test-exhaustive's). Its levels 7 and 8 carry part of the term: the gradient
    traced to 6 levels is further from the 8 levels' than the tolerance (measured: 10.761, 17.8% less). At 12
    levels, measured once: 13.370 against 13.304, 0.49% (the interior 64.7% off; 8.6e9 tree nodes walked)."""
    name = "objects.occ.vertices"
    u = step(pipe_scene, name, 4)
    check_against_differences(pipe_scene, name, u, positive, 2e-2, TOL, CONTROL, k=1)
    deep, shallow = (float((gradient(lambda: pipe_scene(SPP, d), [name], positive, True)[name] * u).sum())
                     for d in (8, 6))
    assert abs(shallow - deep) > TOL * abs(deep), (shallow, deep)


def test_the_glass_slab_scene_past_six_levels_has_its_edges():
    """scenes/glass_slab.toml, traced to 8 ray levels, was refused edges=True (past 6): at 4 x 2 pixels its
    backward(edges=True) in the stripes' vertices and the camera runs, its edges' term is not 0, and two runs give
    the same gradient to the bit."""
    s = warprt.load_scene(ROOT / "scenes" / "glass_slab.toml").with_camera(width=4, height=2).with_render(spp=1)
    assert s.render.max_depth == 8
    d = np.random.default_rng(3).random((2, 4, 3)).astype(np.float32)
    names = ["objects.stripes hi.vertices", "camera.eye"]
    runs = [gradient(lambda: s, names, d, True) for _ in range(2)]
    interior = gradient(lambda: s, names, d, False)
    for name in names:
        assert np.array_equal(runs[0][name], runs[1][name]), name
        assert not np.allclose(runs[0][name], interior[name]), name


def test_the_glass_edges_gradient_is_the_same_on_every_run_and_thread_count(weights):
    """Each crossing's rays and adjoints are its own, summed on the host in the crossings' order: two runs, and
    one thread against two, give the same gradient to the bit."""
    names = ["objects.occ.vertices", "objects.wall.vertices", "lights.0.position", "materials.glass.ior"]
    runs = [gradient(lambda: slab_scene(4), names, weights, True, threads=t) for t in (1, 1, 2)]
    for other in runs[1:]:
        for name in names:
            assert np.array_equal(runs[0][name], other[name]), name


def test_the_camera_edges_and_the_crossings_count_the_glass_outline_once(positive):
    """The camera's boundary term through the slab found two ways: the camera edges' term (the edges seen
    directly, integrated at Gauss points) plus the crossings below the glass's split (edges=True less edges=False),
    and the crossings at every node alone, each boundary once by construction; they agree (measured: 0.3% of the
    largest eye component, 0.2% of fovy), which they would not if the outline seen directly and the band just
    inside it were counted by both (the double count _theirs_near takes away: the slab's eye was 1.70 against 1.55).
    The control: the crossings below the split alone are far off (they are the smaller part)."""
    assert_camera_term_found_two_ways(slab_scene(1), positive, 0.02)


def assert_camera_term_found_two_ways(s, weights, tol: float):
    """The camera's boundary term (eye, fovy) of a grad frame of ``s``: the camera edges' term plus the crossings
    below the split or bounce (edges=True less edges=False) within ``tol`` of the largest component of the
    crossings at every node alone; the control, the crossings below alone, more than 30% off."""
    r = warprt.Renderer(s)
    r.render(grad=True)
    names = ["camera.eye", "camera.fovy"]
    edges, interior = r.backward(weights, wrt=names, edges=True), r.backward(weights, wrt=names, edges=False)
    every, below = (_crossing_terms(s, r, weights, through) for through in (False, True))
    for name in names:
        key = name.split(".")[1]
        want = sum(np.asarray(t.camera[key]) for t in every)
        got = np.asarray(edges[name]) - np.asarray(interior[name])
        scale = np.abs(want).max()
        assert np.abs(got - want).max() <= tol * scale, (name, got, want)
        assert np.abs(sum(np.asarray(t.camera[key]) for t in below) - want).max() > 0.3 * scale, name
    r.close()


# The camera along each axis of the eye (a random direction's derivative is a small difference of the axes' parts
# here: seed 7's on the ball -1.44 against -1.19 and -1.27, the parts 38 to 76), with its measured error and the
# interior's. The step: 1e-2 (h and h / 2 within the differences' gate); at 4e-2 the differences are
# biased by the loss's bend (the slab's y, rows 0-3 alone: 29.81, 30.65, 30.93 at h 4e-2, 2e-2, 1e-2, 128 x 128
# strata, against 30.89 here). The slab's about 20 s a case, the ball's about a minute: make test-exhaustive's.
X, Y, Z = (1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0)
CAMERA = [(slab_scene, "camera.eye", X, 1e-2),  # 1.71% (interior 110%; 0.56% against 128 x 128 strata)
          (slab_scene, "camera.eye", Y, 1e-2),  # 0.35% (112%)
          (slab_scene, "camera.eye", Z, 1e-2),  # 2.36% (106%; 0.88% against 128 x 128)
          (ball_scene, "camera.eye", X, 1e-2),  # 1.99% (136%)
          (ball_scene, "camera.eye", Y, 1e-2),  # 0.65% (126%)
          (ball_scene, "camera.eye", Z, 1e-2),  # 2.10% (76%)
          # the same speeds' other camera adjoints; fovy in degrees (at 4e-2 the image moves by under a stratum)
          (slab_scene, "camera.center", X, 1e-2),  # 0.97% (77%)
          (slab_scene, "camera.up", X, 1e-2),  # 0.69% (107%)
          (slab_scene, "camera.fovy", 1.0, 0.5),  # 0.47% (117%)
          (ball_scene, "camera.fovy", 1.0, 0.5)]  # 2.27% (67%)


@pytest.mark.parametrize("make, name, u, h", [pytest.param(*case, id=f"{case[0].__name__}-{case[1]}-{i}",
                                                           marks=(slow, exhaustive)) for i, case in enumerate(CAMERA)])
def test_the_camera_through_glass_equals_central_differences(positive, make, name, u, h):
    """The camera through the slab and the smooth glass ball (their outlines seen directly, the triangle and its
    shadow seen through them, all moved by the camera) against the differences of the converged forward, every
    pixel kept; the control: the interior derivative alone (edges=False) is far off."""
    check_against_differences(make, name, np.asarray(u, np.float64), positive, h, TOL, CONTROL, k=1)


# A dielectric's ior, which bends what is seen through it (the edges seen directly, the shadows and the planar mirrors'
# do not move with it), with its measured error and the interior's. The slab's derivative is a small difference of
# large parts (the interior -9.67, the crossings' term +10.47), so 3% of it is 0.23% of the term. The steps: where h
# and h / 2 agree; at 64 x 64 strata a smaller one moves the image by under a stratum (the slab's differences 0.809,
# 0.805, 1.130, 1.554 at h 4e-2 to 5e-3; at 128 x 128 strata 0.800, 0.817, 1.078 at 2e-2 to 5e-3), and the ball's
# loss bends within 2e-2 (-19.53, -21.01, -20.18, -20.35 at h 4e-2 to 5e-3; -20.99, -20.06, -20.34 at 128 x 128).
IOR = [(slab_scene, 4e-2),  # 0.20%: 0.8052 against 0.8068 (interior -9.668, 1298%)
       (ball_scene, 1e-2)]  # 0.04%: -20.273 against -20.265 (interior 3.954, 120%)


@pytest.mark.parametrize("make, h", [pytest.param(*case, id=case[0].__name__,
                                                  marks=(slow,) if i == 0 else (slow, exhaustive))
                                     for i, case in enumerate(IOR)])
def test_the_ior_through_glass_equals_central_differences(positive, make, h):
    """materials.glass.ior: the triangle and its shadow seen through the slab and the smooth ball (and the slab's
    own far creases seen through its front) move as the ior bends the rays (the crossings' speed in each
    refraction's eta), against the differences of the converged forward, every pixel kept; the control: the
    interior derivative alone (edges=False, Fresnel's and Snell's change at the held faces) is far off."""
    check_against_differences(make, "materials.glass.ior", np.asarray(1.0), positive, h, TOL, CONTROL, k=1)




def wave_step(make, name: str, seed: int, number: float = 2.0) -> np.ndarray:
    """A smooth random direction for an object's vertices: per component 0.3 sin(k . (p - c) + phase) at each rest
    vertex p (c: their mean), k random of about ``number`` a unit. A random step a vertex (step) crumples a smooth
    glass ball, whose loss then bends within 1e-3 of the step (seed 4: the slope +110 on one side of t = 0.0015,
    -120 on the other; at h 2.5e-3 the differences' h and h / 2 read 73.3 and 77.1) while its edges' term is a few
    per cent of it (the interior alone within 5% of the differences): no check of the term. A smooth field turns
    the ball's normals and bends its outline, and the loss along it is smooth."""
    r = warprt.Renderer(make())
    p = np.asarray(r.params[name], np.float64)
    r.close()
    rng = np.random.default_rng(seed)
    k, phase = rng.standard_normal((3, 3)) * number, rng.uniform(0.0, 2.0 * np.pi, 3)
    return 0.3 * np.sin((p - p.mean(axis=0)) @ k.T + phase)


# A glass object's own vertices and pose (issue 38): they move its outline seen directly (the camera edges' term),
# its creases seen through it, what it bends and its shadow (the crossings: its faces on the speed's path, a smooth
# glass's vertex normals taken back to its vertices), at once. (scene, name, direction, h), each with its measured
# error and the interior's; the ball's vertices along a smooth field (wave_step), with its normals held in the speed
# 21% off.
OWN = [(slab_scene, "objects.slab.vertices", (step, 4), 2e-2),  # 0.07% (interior 98.6%)
       (slab_scene, "objects.slab.translation", (step, 6), 2e-2),  # 0.31% (100%)
       (slab_scene, "objects.slab.rotation", (step, 6), 2e-2),  # 0.41% (99.7%)
       (ball_scene, "objects.ball.vertices", (wave_step, 4), 1e-2),  # 0.69% (101%)
       (ball_scene, "objects.ball.translation", (step, 6), 2e-2)]  # 0.10% (76%)
OWN_SUITE = {0}  # make test's: the slab's vertices; the rest make test-exhaustive's


@pytest.mark.parametrize("make, name, direction, h", [
    pytest.param(*case, id=f"{case[0].__name__}-{case[1]}",
                 marks=(slow,) if i in OWN_SUITE else (slow, exhaustive)) for i, case in enumerate(OWN)])
def test_the_glass_own_vertices_and_pose_equal_central_differences(positive, make, name, direction, h):
    """A glass object's own vertices, translation and rotation, flat and smooth, against the differences of the
    converged forward, every pixel kept; the control: the interior derivative alone (edges=False) is far off."""
    how, seed = direction
    check_against_differences(make, name, how(make, name, seed), positive, h, TOL, CONTROL, k=1)


def test_a_smooth_glass_own_vertices_term_is_linear_in_the_image_adjoint(weights):
    """The smooth ball's vertices' term the same on a second backward of the frame, and the sum of two halves of
    the image adjoint's that of the whole: its normals' adjoint is taken back to its vertices through sums made
    again at each call (the control, measured: with the sums made once and launched again, they doubled, the
    second set of lines' share of the normals came out halved and the second backward differed)."""
    s = ball_scene(1)
    r = warprt.Renderer(replace(s, camera=replace(s.camera, width=WIDTH // 2, height=HEIGHT // 2)))  # its lines a
    r.render(grad=True)  # quarter of the full frame's
    name = "objects.ball.vertices"
    weights = weights[:HEIGHT // 2, :WIDTH // 2]
    top = weights.copy()
    top[HEIGHT // 4:] = 0.0
    first, again = (r.backward(weights, wrt=[name], edges=True)[name] for _ in range(2))
    halves = r.backward(top, wrt=[name], edges=True)[name] + r.backward(weights - top, wrt=[name], edges=True)[name]
    r.close()
    assert np.array_equal(first, again)
    np.testing.assert_allclose(halves, first, rtol=0.0, atol=1e-5 * np.abs(first).max())


def checker_wall(s):
    """``s`` with a checker on its wall, the wall's corners at the unit square's uv: about 4 squares a unit of uv
    each way, turned and sheared so that their lines lie slanted in the image. Along the pixels' rows or columns
    a line moves a whole row of the differences' strata at once: a staircase (the slab's camera.eye x, axis-aligned
    squares: slopes 6.3 to 9.3 between steps of 5e-3; slanted: 14.4 to 16.4)."""
    mats = dict(s.materials)
    mats["wall"] = replace(mats["wall"], kd_texture=Texture(checker=((1.0, 1.0, 1.0), (0.3, 0.3, 0.3)),
                                                            uv_transform=(3.5, 1.5, 0.1, -1.3, 3.4, 0.2)))
    corners = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    return replace(s, materials=mats, objects=[replace(o, uv=corners) if o.name == "wall" else o for o in s.objects])


def hard_spot(s, direction: tuple, cutoff: float = 25.0):
    """``s`` with its light a hard spot along ``direction`` (``cutoff`` degrees, no ramp)."""
    spot = warprt.Light(type="spot", position=s.lights[0].position, direction=direction, cutoff_angle=cutoff,
                        beam_width=cutoff)
    return replace(s, lights=[spot])


def _with_checker_wall(spp: int = SPP):
    """slab_scene with a checker on its wall (checker_wall)."""
    return checker_wall(slab_scene(spp))


def filled_quad_scene(spp: int = SPP):
    """test_checker_edges.quad_scene seen closer (fovy 25 degrees) and turned (up tilted): the checkered quad
    fills the view, no outline of it in view, its lines slanted in the image (along the pixels' rows or columns
    the crossings' quadrature is coarser: 7.6% of the largest vertex component at LINES 16, 0.8% at 64)."""
    s = quad_scene(spp)
    return replace(s, camera=replace(s.camera, fovy=25.0, up=(0.4, 1.0, 0.0)))


def test_the_checker_crossings_agree_with_the_checker_edges_term(positive):
    """Without glass, every crossing counted (through=False): the crossings' term in the checkered quad's vertices
    and the camera's eye, where the squares part the signatures (kernels.glass_edges.checker_squares, the parting's
    CHECKER_LINE), is the direct checker lines' term (edges=True less edges=False: image/grad_checker_edges.py, an
    independent method, the lines cut into segments integrated at Gauss points) within the lines' quadrature
    (measured: 3.1% of the largest vertex component, 2.4% of the eye's; 0.66% and 1.5% at LINES 32, 0.49% and
    0.29% at 64); the control: with the squares left out of the signatures (EdgeFrame.square_bits) the crossings
    find no line and are far off (116%, 349%)."""
    s = filled_quad_scene(1)
    r = warprt.Renderer(s)
    r.render(grad=True)
    names = ["objects.quad.vertices", "camera.eye"]
    edges, interior = r.backward(positive, wrt=names, edges=True), r.backward(positive, wrt=names, edges=False)
    for bits in (True, False):
        terms = _crossing_terms(s, r, positive, False, square_bits=bits)
        got = {names[0]: sum(t.points for t in terms), names[1]: sum(np.asarray(t.camera["eye"]) for t in terms)}
        for name in names:
            want = edges[name] - interior[name]
            scale = np.abs(want).max()
            off = np.abs(got[name] - want).max()
            assert off <= 0.04 * scale if bits else off > 0.3 * scale, (name, bits, got[name], want)
    r.close()


# The checker wall seen through the slab (its lines the crossings' CHECKER_LINE partings), each with its measured
# error, the interior's, and edges=True's with the squares left out of the crossings' signatures (EdgeFrame.square_bits,
# measured once). The wall's vertices (seed 3: of 12 seeds the one whose term the squares carry most) move its squares,
# shadow and outline; the eye's z is the axis the squares move most (x and y: edges=True without them 10% and 11% from
# with them). make test's case as long as the slab's occluder case (about 100 s each on 2 loaded cores).
CHECKER = [(_with_checker_wall, "objects.wall.vertices", 3, 4e-2),  # 0.14% (interior 69%, without the squares 78%)
           (_with_checker_wall, "camera.eye", Z, 2e-2)]  # 0.73% (104%, 17%)


@pytest.mark.parametrize("make, name, u, h", [
    pytest.param(*case, id=f"checker-{case[1]}", marks=(slow,) if i == 0 else (slow, exhaustive))
    for i, case in enumerate(CHECKER)])
def test_a_checker_seen_through_glass_equals_central_differences(positive, make, name, u, h):
    """A checker's lines seen through the slab, moved by the wall's vertices and the camera, against the
    differences of the converged forward, every pixel kept; the control: the interior derivative alone
    (edges=False) is far off."""
    along = step(make, name, u) if isinstance(u, int) else np.asarray(u, np.float64)
    check_against_differences(make, name, along, positive, h, TOL, CONTROL, k=1)


def assert_refused(scene, weights, name: str, words: list, covered: tuple = ()):
    """backward(edges=True) in ``name`` at a grad frame of ``scene`` raises one line naming ``edges`` and holding
    each of ``words``; edges=False does not, nor edges=True in the ``covered`` parameters."""
    r = warprt.Renderer(scene)
    r.render(grad=True)
    with pytest.raises(warprt.SceneError, match="edges") as e:
        r.backward(weights, wrt=[name], edges=True)
    assert all(w in str(e.value) for w in words) and "\n" not in str(e.value), str(e.value)
    r.backward(weights, wrt=[name], edges=False)
    if covered:
        r.backward(weights, wrt=list(covered), edges=True)
    r.close()
