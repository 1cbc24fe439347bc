"""The boundary term of the edges camera rays see (issue 38's first edge kind; backward(edges=True),
image/grad_edges.py): the derivative of the box-filtered pixel integral in objects' vertices and the camera,
silhouettes against the background and against an object behind, and a box's flat creases, against central
differences of the forward at 64 x 64 strata a pixel (no pixel masked), each with the control that the
interior derivative alone (edges=False) is far off; the edge function's derivative against Warp's gradcheck
and a closed form; the sum the same to the bit on every run and thread count; the scenes whose other edges
would move refused (shadows' edges: test_shadow_edges.py).
"""

from __future__ import annotations

import numpy as np
import pytest
import warp as wp
import warp.autograd

import warprt
from warprt.image import MAX_GLASS_DEPTH, EdgeFrame, camera_edges, edge_points, edge_sides, segment_points
from warprt.kernels import edge_distances
from warprt.scene import camera_basis, resolve_effects

from .converged import differences, gradient

WIDTH, HEIGHT = 24, 18
SPP = 256  # the gradient frame's: 16 x 16 strata (the differences': converged.FD_SPP)
TOL = 0.02  # measured: within 0.4% of the differences, 1.5% for the ball's camera.eye (0.4% of those at 256 x 256
# samples a pixel: the differences' own error)
LIGHT = {"position": [2.0, 3.0, 4.0], "color": [0.8, 0.8, 0.7]}
TRIANGLE = [[-1.0, -0.8, 0.0], [1.1, -0.6, 0.2], [0.1, 0.9, -0.1]]
BACK = [[-1.6, -1.1, -1.5], [0.9, -1.2, -1.4], [1.0, 1.0, -1.6], [-1.4, 0.9, -1.5]]  # partly behind the box


def triangle_scene(spp: int = SPP, **render):
    """A flat-shaded triangle against the background, every edge in view."""
    return warprt.load_dict({
        "camera": {"eye": [0.0, 0.0, 4.0], "center": [0.0, 0.0, 0.0], "width": WIDTH, "height": HEIGHT, "fovy": 40.0},
        "render": {"ambient": [0.2] * 3, "max_depth": 1, "shadows": False, "spp": spp,
                   "background": [0.1, 0.2, 0.3], **render},
        "lights": [LIGHT], "materials": {"red": {"kd": [0.7, 0.2, 0.1], "ks": [0.3] * 3, "shininess": 20.0}},
        "objects": [{"shape": "triangles", "name": "tri", "vertices": TRIANGLE, "faces": [[0, 1, 2]],
                     "material": "red"}]})


def box_scene(spp: int = SPP, wall_kr=(0.0, 0.0, 0.0), lights=None, crate=None, **render):
    """A turned flat-shaded box (silhouette and creases in view) in front of a quad whose edges it hides in
    part, the quad's other edges against the background; ``wall_kr``: the quad's reflectivity. Turned about
    each axis, so that no edge's image lies along the pixels' strata (a staircase of a row of samples at once
    the differences would not resolve); both lights on the camera's side, no visible face near its terminator.
    ``lights``, ``crate``: other lights, the crate's material's other fields."""
    return warprt.load_dict({
        "camera": {"eye": [0.5, 1.0, 4.0], "center": [0.0, 0.0, 0.0], "width": WIDTH, "height": HEIGHT, "fovy": 45.0},
        "render": {"ambient": [0.2] * 3, "max_depth": 1, "shadows": False, "spp": spp,
                   "background": [0.1, 0.2, 0.3], **render},
        "lights": lights or [LIGHT, {"position": [-1.5, 2.0, 4.5], "color": [0.3, 0.4, 0.5]}],
        "materials": {"crate": {"kd": [0.6, 0.3, 0.1], "ks": [0.4] * 3, "shininess": 30.0, **(crate or {})},
                      "wall": {"kd": [0.2, 0.5, 0.6], "ks": [0.1] * 3, "shininess": 8.0,
                               "reflectivity": list(wall_kr)}},
        "objects": [{"shape": "box", "name": "crate", "size": [1.2, 1.0, 1.0], "rotate": [25.0, 35.0, 25.0],
                     "translate": [0.2, 0.1, 0.0], "material": "crate"},
                    {"shape": "triangles", "name": "back", "vertices": BACK, "faces": [[0, 1, 2], [0, 2, 3]],
                     "material": "wall"}]})


def ball_scene(spp: int = SPP, **render):
    """A smooth ball (an icosphere, its normals computed: they follow the vertices) against the background and
    in front of the quad: its silhouette the only edge where its image jumps."""
    return warprt.load_dict({
        "camera": {"eye": [0.3, 0.5, 4.0], "center": [0.0, 0.0, 0.0], "width": WIDTH, "height": HEIGHT, "fovy": 45.0},
        "render": {"ambient": [0.2] * 3, "max_depth": 1, "shadows": False, "spp": spp,
                   "background": [0.1, 0.2, 0.3], **render},
        "lights": [LIGHT], "materials": {"ball": {"kd": [0.6, 0.3, 0.1], "ks": [0.5] * 3, "shininess": 30.0},
                                         "wall": {"kd": [0.2, 0.5, 0.6], "ks": [0.1] * 3, "shininess": 8.0}},
        "objects": [{"shape": "sphere", "name": "ball", "subdivisions": 2, "smooth": True, "scale": 0.8,
                     "translate": [0.3, 0.0, 0.0], "material": "ball"},
                    {"shape": "triangles", "name": "back", "vertices": BACK, "faces": [[0, 1, 2], [0, 2, 3]],
                     "material": "wall"}]})


@pytest.fixture(scope="module")
def weights():
    return np.random.default_rng(11).random((HEIGHT, WIDTH, 3)).astype(np.float32)


def step(scene, name: str, seed: int) -> np.ndarray:
    """A random direction for one parameter (vertices: one step per vertex; the box's corners are shared), of
    0.3 a component (fovy: 3 degrees)."""
    shape = np.shape(warprt.Renderer(scene).params[name])
    return np.random.default_rng(seed).standard_normal(shape) * (3.0 if name == "camera.fovy" else 0.3)


CASES = [(triangle_scene, "objects.tri.vertices", 4), (triangle_scene, "objects.tri.vertices", 12),
         (triangle_scene, "camera.eye", 5), (box_scene, "objects.crate.vertices", 6),
         (box_scene, "objects.crate.vertices", 10), (box_scene, "objects.back.vertices", 8),
         (box_scene, "camera.eye", 9), (ball_scene, "objects.ball.vertices", 13), (ball_scene, "camera.eye", 19),
         (box_scene, "camera.center", 22), (triangle_scene, "camera.fovy", 23),
         # an object's pose: its vertices' edge term taken back through the pose (grad.pose_edge_gradients)
         (box_scene, "objects.crate.translation", 31), (box_scene, "objects.crate.rotation", 32)]


@pytest.mark.parametrize("make, name, seed", CASES,
                         ids=[f"{m.__name__}-{n}-{s}" for m, n, s in CASES])
def test_the_edges_gradient_equals_central_differences(weights, make, name, seed):
    """edges=True against the differences of the converged forward, every pixel kept; the control: the
    interior derivative alone (edges=False) misses the moving edges' term by far."""
    u = step(make(), name, seed)
    fd = differences(make, name, u, weights)
    with_edges = float((gradient(make, [name], weights, True)[name] * u).sum())
    interior = float((gradient(make, [name], weights, False)[name] * u).sum())
    assert abs(with_edges - fd) <= TOL * abs(fd), (with_edges, fd)
    assert abs(interior - fd) > 0.1 * abs(fd), (interior, fd)


def test_edges_hidden_behind_the_box_have_no_jump():
    """The quad's edges behind the box: both rays either side meet the box, so f_+ - f_- is the box's shading
    over 1e-3 of a pixel (about 0), where the same edges' visible parts jump by the quad's contrast with the
    background; the box's silhouette and creases are found, its hidden back edges too (drawn from the eye)."""
    s = box_scene()
    r = warprt.Renderer(s, aovs=("object",))
    seen = r.render().aovs["object"].reshape(HEIGHT, WIDTH)
    geom = r.geometry
    eye = geom.eye_offset(s.camera.eye).astype(np.float64)
    fx = resolve_effects(s)
    edges = camera_edges(s, geom, fx, eye)
    pts = edge_points(edges, geom.points_np.astype(np.float64), eye, s.camera)
    jump = np.abs(edge_sides(s, geom, EdgeFrame(fx, 0, 1), pts, "cpu")).max(axis=1)
    back = pts.edges[pts.edge, 0] >= 8  # the quad's vertices follow the box's 8
    padded = np.pad(seen, 1, constant_values=-1)
    inside = np.ones_like(seen, bool)  # pixels whose 3 x 3 neighbourhood shows only the box (object 0)
    for dy in range(3):
        for dx in range(3):
            window = padded[dy:dy + HEIGHT, dx:dx + WIDTH]
            inside &= window == 0
    hidden = back & inside.reshape(-1)[pts.pixel]
    assert hidden.sum() > 4 and (back & ~hidden).sum() > 4
    assert jump[hidden].max() < 1e-3
    assert np.median(jump[back & ~hidden]) > 0.05
    r.close()


def _distance_inputs(n: int, seed: int = 2):
    """Random edges, each point on its own edge's image (its distance 0), and a camera per point."""
    rng = np.random.default_rng(seed)
    s = triangle_scene()
    cam = s.camera
    v0 = rng.uniform(-1, 1, (n, 3)) * [1, 1, 0.3]
    v1 = rng.uniform(-1, 1, (n, 3)) * [1, 1, 0.3]
    eye = np.asarray(cam.eye, np.float64)
    edges = np.arange(2 * n).reshape(n, 2)
    pts = edge_points(edges, np.concatenate([v0, v1], axis=1).reshape(-1, 3), eye, cam)
    first = np.unique(pts.edge, return_index=True)[1]  # one point per edge in view
    at = pts.at[first]
    keep = pts.edge[first]
    camera = np.tile(np.stack([eye, np.asarray(cam.center), np.asarray(cam.up)]), (len(keep), 1))
    return v0[keep], v1[keep], camera, np.full(len(keep), cam.fovy), at, cam


@pytest.mark.parametrize("family, cut", [((0, 1), False), ((0, 0), True), ((-1, 1), True), (None, True)])
def test_segments_of_two_families_do_not_cut_each_other(family, cut):
    """Two segments whose images cross inside a pixel: cut there (each piece its own Gauss points) unless both
    have a family and they differ (two sources' shadow edges: each one's jump is smooth across the other's).
    Either way each segment's weights sum to its image's length, and a linear function along it integrates exactly
    (the midpoint rule's)."""
    cam = triangle_scene().camera
    eye = np.asarray(cam.eye, np.float64)
    q0 = np.array([[-0.61, -0.23, 0.0], [-0.52, 0.37, 0.0]]) - eye
    q1 = np.array([[0.58, 0.31, 0.0], [0.49, -0.29, 0.0]]) - eye
    with_family = segment_points(q0, q1, np.cross(q0, q1), cam, family=None if family is None else np.array(family))
    alone = [segment_points(q0[i:i + 1], q1[i:i + 1], np.cross(q0[i:i + 1], q1[i:i + 1]), cam) for i in range(2)]
    b = camera_basis(cam)
    for i in range(2):
        mine = with_family.edge == i
        assert (mine.sum() > len(alone[i].edge)) == cut  # the crossing's cut: one piece more, its Gauss points
        ends = [(b.width * (0.5 + b.d_f * (q @ b.x_e) / (-(q @ b.z_e) * b.w)),
                 b.height * (0.5 + b.d_f * (q @ b.y_e) / (-(q @ b.z_e) * b.h))) for q in (q0[i], q1[i])]
        a, c = np.asarray(ends[0]), np.asarray(ends[1])
        length = np.linalg.norm(c - a)
        s = (with_family.at[mine] - a) @ (c - a) / length ** 2  # each point's parameter along the image
        assert with_family.weight[mine].sum() == pytest.approx(length, rel=1e-12)
        assert (with_family.weight[mine] * (0.5 + 3.0 * s)).sum() == pytest.approx(length * 2.0, rel=1e-10)


def test_fine_segments_integrate_a_turning_jump_at_more_points():
    """A segment marked ``fine`` (a curved mirror's rim: grad_mesh_edges.rims) gets FINE_POINTS Gauss points a piece,
    on the same pieces: cos(9 s) along its image, a jump that turns within a pixel, integrates to its closed form
    sin(9) / 9 times the length within 1e-9; the control, one point a piece (the midpoint), is 1e-4 off or more."""
    cam = triangle_scene().camera
    eye = np.asarray(cam.eye, np.float64)
    q0, q1 = np.array([[-0.61, -0.23, 0.0]]) - eye, np.array([[0.58, 0.31, 0.0]]) - eye
    b = camera_basis(cam)
    ends = [np.array([b.width * (0.5 + b.d_f * (q @ b.x_e) / (-(q @ b.z_e) * b.w)),
                      b.height * (0.5 + b.d_f * (q @ b.y_e) / (-(q @ b.z_e) * b.h))]) for q in (q0[0], q1[0])]
    length = np.linalg.norm(ends[1] - ends[0])
    sums = []
    for fine in (np.array([True]), None):
        pts = segment_points(q0, q1, np.cross(q0, q1), cam, fine=fine)
        s = (pts.at - ends[0]) @ (ends[1] - ends[0]) / length ** 2
        assert pts.weight.sum() == pytest.approx(length, rel=1e-12)
        sums.append((pts.weight * np.cos(9.0 * s)).sum())
    assert abs(sums[0] - length * np.sin(9.0) / 9.0) <= 1e-9 * length
    assert abs(sums[1] - length * np.sin(9.0) / 9.0) >= 1e-4 * length


def test_the_edge_distance_passes_warps_gradcheck():
    """edge_distances' adjoints (vertices, eye, center, up, fovy) against Warp's own finite differences."""
    v0, v1, camera, fovy, at, cam = _distance_inputs(6)
    vec = lambda a: wp.array(a.astype(np.float32), dtype=wp.vec3, requires_grad=True)  # noqa: E731
    inputs = [vec(v0), vec(v1), vec(camera), wp.array(fovy.astype(np.float32), dtype=float, requires_grad=True),
              float(cam.near), cam.width, cam.height, wp.array(at.astype(np.float32), dtype=wp.vec2)]
    out = wp.zeros(len(v0), dtype=float, requires_grad=True)
    assert warp.autograd.gradcheck(edge_distances, dim=len(v0), inputs=inputs, outputs=[out], eps=1e-3, atol=2e-2,
                                   rtol=2e-2, show_summary=False, raise_exception=False)


def test_the_edge_speed_is_the_closed_form():
    """On the edge, d distance / d v0 = ((v1 - eye) x d) / |grad_x g| for g = det(v0 - eye, v1 - eye, d(x))
    (NumPy, float64, the camera's own basis): Reynolds' v . n = d_theta g / |grad_x g|; its negative, the
    control, is not."""
    v0, v1, camera, fovy, at, cam = _distance_inputs(6)
    n = len(v0)
    vec = lambda a: wp.array(a.astype(np.float32), dtype=wp.vec3, requires_grad=True)  # noqa: E731
    a0, a1 = vec(v0), vec(v1)
    out = wp.zeros(n, dtype=float, requires_grad=True)
    tape = wp.Tape()
    with tape:
        wp.launch(edge_distances, dim=n, inputs=[a0, a1, vec(camera), wp.array(fovy.astype(np.float32), dtype=float,
                  requires_grad=True), float(cam.near), cam.width, cam.height,
                  wp.array(at.astype(np.float32), dtype=wp.vec2)], outputs=[out])
    tape.backward(grads={out: wp.array(np.ones(n, np.float32), dtype=float)})
    b = camera_basis(cam)
    eye = np.asarray(cam.eye, np.float64)
    d = -b.d_f * b.z_e + b.h * (at[:, 1:2] / b.height - 0.5) * b.y_e + b.w * (at[:, 0:1] / b.width - 0.5) * b.x_e
    nrm = np.cross(v0 - eye, v1 - eye)
    grad_x = np.hypot(nrm @ b.x_e * b.w / b.width, nrm @ b.y_e * b.h / b.height)
    expected = np.cross(v1 - eye, d) / grad_x[:, None]
    np.testing.assert_allclose(a0.grad.numpy(), expected, rtol=2e-3, atol=2e-3 * np.abs(expected).max())
    assert np.abs(a0.grad.numpy() + expected).max() > 0.5 * np.abs(expected).max()


def test_the_edges_gradient_is_the_same_on_every_run_and_thread_count(weights):
    """The edges' sums run in a fixed order (one launch a step, each point its own adjoints, np.add.at on the
    host): two runs, and one thread against two, give the same gradient to the bit."""
    names = ["objects.crate.vertices", "objects.back.vertices", "camera.eye", "camera.fovy"]
    runs = [gradient(box_scene, names, weights, True, threads=t) for t in (1, 1, 2)]
    for other in runs[1:]:
        for name in names:
            assert np.array_equal(runs[0][name], other[name]), name


REFUSED = {"glass": ({"max_depth": MAX_GLASS_DEPTH + 1, "crate": {"ior": 1.5, "transmittance": [0.9] * 3}},
                     "ray levels")}
# (a checker's squares and a hard spot's cone seen in a planar mirror: covered, test_mirror_checker_spot.py)


@pytest.mark.parametrize("shadows", [False, True], ids=["no shadows", "shadows"])
@pytest.mark.parametrize("case", list(REFUSED))
def test_edges_are_refused_where_other_edges_move(weights, case, shadows):
    """A scene whose named parameters also move edges this derivative does not cover: one line naming
    ``edges``, with shadows traced or not (a shadow's edges are covered: test_shadow_edges.py; those seen in a
    planar mirror too: test_mirror_edges.py, and through glass to 12 ray levels: test_glass_edges.py, deeper not); a
    parameter that moves no edge (a
    colour) is not refused, and edges=False never is."""
    kwargs, why = REFUSED[case]
    r = warprt.Renderer(box_scene(**kwargs, shadows=shadows))
    r.render(grad=True)
    with pytest.raises(warprt.SceneError, match="edges") as e:  # an ArgumentError
        r.backward(weights, wrt=["objects.crate.vertices"], edges=True)
    assert why in str(e.value)
    r.backward(weights, wrt=["materials.crate.kd"], edges=True)
    r.backward(weights, wrt=["objects.crate.vertices"], edges=False)
    r.close()


def test_a_light_moves_no_camera_edge_without_shadows(weights):
    """With shadows off and one ray level, a point light's position moves no edge: edges=True is the interior
    derivative, to the bit."""
    r = warprt.Renderer(box_scene())
    r.render(grad=True)
    names = ["lights.0.position", "materials.crate.kd"]
    a, b = r.backward(weights, wrt=names, edges=True), r.backward(weights, wrt=names, edges=False)
    assert all(np.array_equal(a[n], b[n]) for n in names)
    r.close()


def test_the_default_is_the_pixels_derivative(weights):
    """backward() with no ``edges`` is backward(edges=True) (issue 38: the derivative of the box-filtered pixel,
    edges included), to the bit; edges=False, the interior derivative, differs by the crate's silhouette's term."""
    r = warprt.Renderer(box_scene(spp=4))
    r.render(grad=True)
    names = ["objects.crate.vertices", "camera.eye"]
    default, edges, interior = (r.backward(weights, wrt=names, **kw) for kw in ({}, {"edges": True}, {"edges": False}))
    for n in names:
        assert np.array_equal(default[n], edges[n]), n
        assert np.abs(interior[n] - edges[n]).max() > 0.05 * np.abs(edges[n]).max(), n
    r.close()
