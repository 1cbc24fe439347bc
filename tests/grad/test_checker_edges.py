"""The boundary term of a checker texture's squares seen by camera rays (issue 38; backward(edges=True),
image/grad_checker_edges.py): the lines u' = k and v' = k of the checker's affine uv map, straight on each
triangle and moving with it, against central differences of the forward at 128 x 128 samples a pixel (no
pixel masked), in the camera and in the textured object's vertices and pose, lines inside its faces and along
its inner edges, partly behind an occluder and in its shadow, each with the control that the interior
derivative alone (edges=False, 0 inside a square) is far off; the line's distance against Warp's gradcheck;
the sum the same to the bit on every run and thread count (a checker seen in a mirror: still refused,
test_silhouette_edges.py).
"""

from __future__ import annotations

import numpy as np
import pytest
import warp as wp
import warp.autograd

import warprt
from marks import exhaustive, slow
from warprt.image import boundary
from warprt.kernels import checker_edge_distances
from warprt.scene import resolve_effects

from .converged import check_edges_term, gradient

WIDTH, HEIGHT = 24, 18
SPP = 256  # the gradient frame's: 16 x 16 strata (the differences': converged.FD_SPP)
TOL = 0.02  # measured: 0.04% to 0.9% of the differences (CASES' comments)
CONTROL = 0.3  # the interior derivative alone is off by more than this share of them (measured: 39% to 118%)
CAMERA = {"eye": [0.3, 0.4, 4.0], "center": [0.0, 0.0, 0.0], "width": WIDTH, "height": HEIGHT, "fovy": 45.0}
CHECKER = {"checker": [[0.9, 0.8, 0.7], [0.1, 0.2, 0.3]]}
QUAD = [[-1.5, -1.2, -0.3], [1.4, -1.0, 0.2], [1.3, 1.1, -0.2], [-1.4, 1.2, 0.1]]
GRID = [[x, y, 0.15 * x - 0.1 * y + 0.05 * x * y] for y in (-1.4, 0.0, 1.4) for x in (-1.4, 0.0, 1.4)]
GRID_FACES = [f for a in (0, 1, 3, 4) for f in ([a, a + 1, a + 4], [a, a + 4, a + 3])]


def _scene(spp: int, shadows: bool, lights: list, materials: dict, objects: list):
    return warprt.load_dict({
        "camera": CAMERA, "render": {"ambient": [0.2] * 3, "max_depth": 1, "shadows": shadows, "spp": spp,
                                     "background": [0.1, 0.2, 0.3]},
        "lights": lights, "materials": materials, "objects": objects})


def quad_scene(spp: int = SPP):
    """A tilted quad under a checker of scale (3.3, 2.7) and offset (0.1, 0.2): its lines cross its two faces
    at slants, none along an edge."""
    return _scene(spp, False, [{"position": [2.0, 3.0, 4.0], "color": [0.8, 0.8, 0.7]}],
                  {"chk": {"kd_texture": {**CHECKER, "scale": [3.3, 2.7], "offset": [0.1, 0.2]}, "ks": [0.2] * 3,
                           "shininess": 10.0}},
                  [{"shape": "triangles", "name": "quad", "vertices": QUAD, "faces": [[0, 1, 2], [0, 2, 3]],
                    "uv": [[0, 0], [1, 0], [1, 1], [0, 1]], "material": "chk"}])


def grid_scene(spp: int = SPP):
    """A smooth, bent 2 x 2 grid of quads under a checker of scale (4, 2): the lines u' = 2 and v' = 1 lie
    along its inner edges (no camera edge: the same uv, material and normals either side), u' = 1 and 3 cross
    its faces; a triangle in front of it hides some of them and casts its shadow over others."""
    return _scene(spp, True, [{"position": [1.0, 1.5, 4.0], "color": [0.8, 0.8, 0.7]}],
                  {"chk": {"kd_texture": {**CHECKER, "scale": [4.0, 2.0]}, "ks": [0.2] * 3, "shininess": 10.0},
                   "occ": {"kd": [0.3, 0.6, 0.2]}},
                  [{"shape": "triangles", "name": "grid", "vertices": GRID, "faces": GRID_FACES, "smooth": True,
                    "uv": [[i / 2, j / 2] for j in range(3) for i in range(3)], "material": "chk"},
                   {"shape": "triangles", "name": "occ", "faces": [[0, 1, 2]], "material": "occ",
                    "vertices": [[-0.5, -0.3, 1.0], [0.4, -0.5, 1.2], [0.0, 0.5, 1.1]]}])


@pytest.fixture(scope="module")
def weights():
    return np.random.default_rng(11).random((HEIGHT, WIDTH, 3)).astype(np.float32)


# measured (edges=True's error against the differences; edges=False's): quad camera.eye 0.15% (68%), vertices
# 0.04% (65%), translation 0.9% (104%; h = 1e-2: at 4e-2 the cubic's differences are 1.2% off those at 1e-2);
# grid vertices 0.12% (118%), camera.eye 0.05% (39%; the differences at 3 x 3 images a pixel: at 2 x 2 they
# scatter by 2% with h, 3.01 at h = 0.04, 2.96 at 0.02, against 3.07 at 3 x 3)
CASES = [(quad_scene, "camera.eye", 5, 4e-2, 2), (grid_scene, "objects.grid.vertices", 5, 4e-2, 2),
         (quad_scene, "objects.quad.vertices", 5, 4e-2, 2), (quad_scene, "objects.quad.translation", 5, 1e-2, 2),
         (grid_scene, "camera.eye", 5, 4e-2, 3)]
QUICK = {0, 1}  # the rest: make test-exhaustive's alone (about 20 to 40 s each on 2 cores)


@pytest.mark.parametrize("make, name, seed, h, k", [
    pytest.param(*case, id=f"{case[0].__name__}-{case[1]}", marks=() if i in QUICK else (slow, exhaustive))
    for i, case in enumerate(CASES)])
def test_the_checker_edges_gradient_equals_central_differences(weights, make, name, seed, h, k):
    """edges=True against the differences of the converged forward, every pixel kept; the control: the
    interior derivative alone (edges=False) misses the moving squares' term by far."""
    check_edges_term(make, name, seed, weights, h, TOL, CONTROL, k)


def test_the_grids_lines_are_found_inside_its_faces_and_along_its_inner_edges():
    """The grid's checker lines: u' = 1 and 3 across each of the 8 faces' halves (8 segments), u' = 2 and v' = 1
    along its 4 inner edges (one segment each, not one per face), none along its outline (a camera edge's)."""
    s = grid_scene()
    r = warprt.Renderer(s)
    r.render(grad=True)
    geom = r.geometry
    b = boundary(s, geom, resolve_effects(s), geom.eye_offset(s.camera.eye).astype(np.float64))
    w = b.checkers.weights
    on_edge = np.all(np.isin(w, (0.0, 1.0)), axis=(1, 2))
    assert len(w) == 12 and on_edge.sum() == 4
    uv = np.asarray([[i / 2, j / 2] for j in range(3) for i in range(3)] + [[0, 0]] * 3)  # the occluder's: none
    uv = uv[geom.indices_np.reshape(-1, 3)]
    ends = np.einsum("kec,kcx->kex", w, uv[b.checkers.face]) * [4.0, 2.0]  # the mapped uv of each end
    along_u = np.isclose(ends[:, 0, 0], ends[:, 1, 0])  # a line u' = k, else v' = k
    assert np.all(along_u | np.isclose(ends[:, 0, 1], ends[:, 1, 1]))
    k = np.where(along_u, ends[:, 0, 0], ends[:, 0, 1])
    assert np.allclose(k, np.round(k), atol=1e-6)
    assert sorted(np.round(k[along_u & ~on_edge]).astype(int)) == [1] * 4 + [3] * 4
    r.close()


def test_the_checker_edge_distance_passes_warps_gradcheck():
    """checker_edge_distances' adjoints (the face's corners, eye, center, up, fovy) against Warp's own finite
    differences, at points near each line's image."""
    s = quad_scene()
    r = warprt.Renderer(s)
    r.render(grad=True)
    geom = r.geometry
    b = boundary(s, geom, resolve_effects(s), geom.eye_offset(s.camera.eye).astype(np.float64))
    pts, seg = b.checker, b.checkers
    first = np.unique(pts.edge, return_index=True)[1][:6]
    faces = geom.indices_np.reshape(-1, 3)[seg.face[pts.edge[first]]]
    cam = s.camera
    camera = np.tile(np.stack([geom.eye_offset(cam.eye), geom.eye_offset(cam.center), np.asarray(cam.up)]),
                     (len(first), 1))
    vec = lambda a: wp.array(np.asarray(a, np.float32).reshape(-1, 3), dtype=wp.vec3, requires_grad=True)  # noqa: E731
    inputs = [vec(geom.points_np[faces]), wp.array(seg.weights[pts.edge[first]].reshape(-1, 3).astype(np.float32),
                                                   dtype=wp.vec3), vec(camera),
              wp.array(np.full(len(first), cam.fovy, np.float32), dtype=float, requires_grad=True), float(cam.near),
              cam.width, cam.height, wp.array(pts.at[first].astype(np.float32), dtype=wp.vec2)]
    out = wp.zeros(len(first), dtype=float, requires_grad=True)
    assert warp.autograd.gradcheck(checker_edge_distances, dim=len(first), inputs=inputs, outputs=[out], eps=1e-3,
                                   atol=2e-2, rtol=2e-2, show_summary=False, raise_exception=False)
    r.close()


def test_the_checker_edges_gradient_is_the_same_on_every_run_and_thread_count(weights):
    """The checker lines' sums run in a fixed order (each point its own adjoints, np.add.at on the host): two
    runs, and one thread against two, give the same gradient to the bit."""
    names = ["objects.grid.vertices", "objects.occ.vertices", "camera.eye", "camera.fovy"]
    runs = [gradient(grid_scene, names, weights, True, threads=t) for t in (1, 1, 2)]
    for other in runs[1:]:
        for name in names:
            assert np.array_equal(runs[0][name], other[name]), name
