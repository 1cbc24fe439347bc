"""The edges of area lights' soft shadows seen through glass and in curved mirrors (issue 38, backward(edges=True);
image/grad_glass_edges.py): each sample point of an area light casts a hard shadow (a point light's wedge), and the
crossings' tree signatures hold the points each node's shadow rays find blocked (kernels/glass_edges.py
hidden_points: their keys' exclusive or), so a sample point's shadow edge seen through the glass's ray tree or in a
curved mirror is a crossing of its own, its jump the point's share of the colour alone (several points' edges lie at
one crossing where a row of the light's points is in one plane with an occluder's edge). Checked:

- an occluder's vertices, the light's center and the camera's eye, against central differences of the forward at
  64 x 64 samples a pixel (tests/grad/converged.py, no pixel masked), each with the control that the interior
  derivative alone (edges=False) is far off, through a flat glass slab, a smooth glass ball and in a smooth mirror
  ball; a rectangle light seen through the slab beside a point light, its own outline moving with its half-edge u;
- a rectangle light aligned with an occluder's edge (each row of its points' wedges one plane, their shadow edges
  coincident), through the slab, against the same differences; and there the crossings parted by several points
  are found (so the case is the one it stands for);
- the control that the crossings' signatures need the points: without them (EdgeFrame.hidden_bits) the crossings
  find no soft shadow's edge and the term is far off;
- the sum the same to the bit on every run and thread count.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

import warprt
from marks import exhaustive, slow
from warprt.image import glass_terms
from warprt.kernels import SOURCE_SAMPLE

from .converged import check_against_differences, gradient
from .test_curved_mirror_edges import ball_scene as mirror_ball_scene
from .test_glass_edges import ball_scene, frame_crossings, slab_scene
from .test_mirror_edges import step

WIDTH, HEIGHT = 24, 18
SPP = 256
TOL = 0.03  # measured: CASES' comments
CONTROL = 0.3


def area_lit(s, center: list, normal: list | None, samples: int = 4, keep_point: bool = False, **shape):
    """``s`` lit by a rectangle light at ``center`` facing ``normal`` (``samples`` points: 2 x 2 by default, four
    hard shadows a soft one; ``shape``: its other keys, half-edges u and v instead of a normal and a size where
    ``normal`` is None), instead of its point light or (``keep_point``) after it."""
    rectangle = {"type": "area", "shape": "rectangle", "radiance": [6.0, 5.0, 4.0], "center": center, **shape}
    if normal is not None:
        rectangle.update(size=[0.6, 0.4], normal=normal)
    light = warprt.load_dict({"lights": [rectangle], "objects": [], "materials": {}}).lights
    return replace(s, lights=(list(s.lights) if keep_point else []) + list(light),
                   render=replace(s.render, light_samples=samples))


def slab(spp: int = SPP):
    """test_glass_edges.slab_scene under a rectangle light where its point light was: the triangle's soft shadow
    on the wall seen through the slab (and the slab's own)."""
    return area_lit(slab_scene(spp), [1.0, 2.5, 3.0], [-0.3, -1.0, -0.8])


def aligned_slab(spp: int = SPP):
    """slab() with the light level (its rows of points along x) and the triangle's lower edge along x: each row's
    two points' wedges through that edge are one plane, their shadow edges one line."""
    s = area_lit(slab_scene(spp), [1.0, 2.5, 3.0], [0.0, -1.0, 0.0])
    occ = np.asarray(s.objects[1].vertices, np.float64).copy()
    occ[1, 1:] = occ[0, 1:]
    return replace(s, objects=[s.objects[0], replace(s.objects[1], vertices=occ), *s.objects[2:]])


def seen_slab(spp: int = SPP):
    """slab_scene keeping its point light, with a rectangle light behind the slab facing the camera, turned in
    its plane (its edges slanted in the image: along the pixels' rows they would move whole rows of the
    differences' strata at once, a staircase): its own outline seen through the slab, and its shadow of the point
    light on the wall."""
    return area_lit(slab_scene(spp), [-0.9, 0.4, -0.6], None, keep_point=True, u=[0.28, 0.1, -0.03],
                    v=[-0.07, 0.19, 0.02])


def glass_ball(spp: int = SPP):
    """test_glass_edges.ball_scene (a smooth glass ball) under a rectangle light where its point light was."""
    return area_lit(ball_scene(spp), [1.5, 2.0, 3.0], [-0.4, -0.6, -0.8])


def mirror_ball(spp: int = SPP):
    """test_curved_mirror_edges.ball_scene (a smooth mirror ball, the triangle and its shadow seen in it only)
    under a rectangle light where its point light was."""
    return area_lit(mirror_ball_scene(spp), [0.6, 0.5, 1.3], [-0.3, -0.2, -1.0])


@pytest.fixture(scope="module")
def positive():
    """Weights of one sign (test_glass_edges' reason)."""
    return np.random.default_rng(11).random((HEIGHT, WIDTH, 3)).astype(np.float32)


# (scene, name, direction: a random step's seed or an axis, h), each with its measured |edges=True - fd| / |fd| and
# the interior's (edges=False), the differences at 64 x 64 strata a pixel (k = 1). The seen light's u (a half-edge:
# it turns and stretches the rectangle) is its shape's check: its size and normal, on the slab, move the soft shadow
# little against the power they add (the interior alone 0.0% and 0.1% off there), and its center's derivative is a
# small difference of its outline's opposite sides (-3.52 at 16 lines a pixel, -2.81 at 32, -3.40 at 64, against
# -3.81 at 128 x 128 strata; at 64 x 64 the differences' h and h / 2 part by 5% to 19%: 3 seeds).
Y_AXIS, X_AXIS = (0.0, 1.0, 0.0), (1.0, 0.0, 0.0)
CASES = [(slab, "objects.occ.vertices", 4, 2e-2),  # 0.30% (interior 121%)
         (aligned_slab, "objects.occ.vertices", 4, 2e-2),  # 0.48% (114%)
         (mirror_ball, "lights.0.center", 5, 2e-2),  # 0.43% (67%)
         (slab, "lights.0.center", 5, 2e-2),  # 0.16% (62%)
         (slab, "camera.eye", Y_AXIS, 2e-2),  # 0.75% (103%)
         (slab, "camera.eye", X_AXIS, 2e-2),  # 2.00% (116%)
         (seen_slab, "lights.1.u", 5, 2e-2),  # 1.65% (100%)
         (glass_ball, "objects.occ.vertices", 4, 2e-2),  # 1.27% (191%)
         (mirror_ball, "objects.occ.vertices", 4, 2e-2)]  # 2.14% (100%)
SUITE = {1, 2}  # make test's (70 s and 50 s): the occluder through the slab under the aligned light (its generic
# edges and its coincident ones) and the light in the mirror ball; the rest make test-exhaustive's


@pytest.mark.parametrize("make, name, direction, h", [
    pytest.param(*case, id=f"{case[0].__name__}-{case[1]}-{i}",
                 marks=(slow,) if i in SUITE else (slow, exhaustive)) for i, case in enumerate(CASES)])
def test_soft_shadows_through_glass_equal_central_differences(positive, make, name, direction, h):
    """edges=True against the differences of the converged forward, every pixel kept; the control: the interior
    derivative alone (edges=False) misses the soft shadow's moving edges (and the seen light's outline) by far."""
    u = step(make, name, direction) if isinstance(direction, int) else np.asarray(direction)
    check_against_differences(make, name, u, positive, h, TOL, CONTROL, k=1)


def _crossings(s, hidden_bits: bool = True) -> tuple:
    """(crossings, renderer): test_glass_edges.frame_crossings of a grad frame of ``s`` (EdgeFrame.hidden_bits:
    ``hidden_bits``)."""
    r = warprt.Renderer(s)
    r.render(grad=True)
    return frame_crossings(s, r, hidden_bits=hidden_bits), r


def test_an_aligned_lights_points_part_one_crossing():
    """In aligned_slab the crossings parted by a sample point's wedge include some where two points' shadow edges
    are one line (the light's row in one plane with the triangle's edge): the same image point twice in a part's
    crossings, from two sources (the first point alone taking their jump would count the row's jump for one)."""
    crossings, r = _crossings(aligned_slab(1))
    r.close()
    twice = 0
    for (pts, _, _, _, light, _), sources, _, _ in crossings:
        area = sources.source[light, 0] == SOURCE_SAMPLE
        at = np.unique(pts.at[area], axis=0)
        sources_at = [set(light[area][np.all(pts.at[area] == p, axis=1)]) for p in at]
        twice += sum(len(s) > 1 for s in sources_at)
    assert twice > 0


def test_without_the_points_in_the_signatures_the_soft_shadow_is_missed(positive):
    """The control of the signatures' points: with them left out (EdgeFrame.hidden_bits False) the crossings find
    none of the sample points' shadow edges seen through the slab: the points' own term (what their light's center,
    size and normal take) is 0, and the occluder's vertices' term, its outline seen through the slab and its soft
    shadow, loses the shadow's part (measured: 21% of its largest component)."""
    s, occ, points = slab(1), [], []
    starts = np.cumsum([0] + [len(o.vertices) for o in s.objects])  # the triangle: objects[1]
    for bits in (True, False):
        crossings, r = _crossings(s, bits)
        t = glass_terms(crossings, positive.reshape(-1, 3).astype(np.float64), len(r.geometry.points_np))
        occ.append(sum(x.points for x in t)[starts[1]:starts[2]])
        points.append(np.abs(sum(x.sources for x in t)).max())
        r.close()
    assert points[0] > 0.0 and points[1] == 0.0, points
    assert np.abs(occ[1] - occ[0]).max() > 0.1 * np.abs(occ[0]).max()


def test_the_soft_shadows_term_is_the_same_on_every_run_and_thread_count(positive):
    """Each crossing's rays and adjoints are its own, summed on the host in the crossings' order: two runs, and one
    thread against two, give the same gradient to the bit."""
    names = ["objects.occ.vertices", "lights.0.center", "lights.0.size", "camera.eye"]
    runs = [gradient(lambda: slab(4), names, positive, True, threads=t) for t in (1, 1, 2)]
    for other in runs[1:]:
        for name in names:
            assert np.array_equal(runs[0][name], other[name]), name
