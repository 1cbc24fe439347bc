"""Triangles that cross the plane of the eye are clipped, not dropped or mirrored: what they show is
computed here in closed form (two planar triangles, float64), independently of both renderers."""

import numpy as np

from marks import slow
from oracle import pinhole, pixel_directions, ray_triangle
from tests.scenekit import make_scene
from tests.zbuffer.test_agreement import FLOOR, LIGHTS, MATERIALS, WALL
from warprt.image import render_zbuffer

MARGIN = 1e-4  # pixels whose ray passes this close (barycentric) to an edge are left out of the oracle


def closed_form_faces(scene, triangles):
    """The nearest of the given world-space triangles along each pixel-centre ray, (H, W); -1 for
    none, -2 where the ray passes within MARGIN of an edge (either answer would be right)."""
    b = pinhole(scene.camera)
    d = pixel_directions(b).reshape(-1, 3)
    best_t = np.full(len(d), np.inf)
    best = np.full(len(d), -1)
    unsure = np.zeros(len(d), bool)
    for i, tri in enumerate(np.asarray(triangles, np.float64)):
        h = ray_triangle(b.eye, d, *tri)
        t, m = h.t, h.margin
        hit = (m > -MARGIN) & (t > 0)
        unsure |= hit & (np.abs(m) <= MARGIN)
        nearer = hit & (m > 0) & (t < best_t)
        best[nearer], best_t[nearer] = i, t[nearer]
    best[unsure] = -2
    return best.reshape(b.height, b.width), (best_t * b.d_f).reshape(b.height, b.width)  # t * d_f: depth


@slow
def test_triangles_crossing_the_eye_plane_match_the_closed_form():
    """The wall has one vertex behind the eye (clipped to a quad), the floor two (clipped to a
    triangle); both reach the eye, so much of what the image shows is nearer than near = 2."""
    scene = make_scene([WALL, FLOOR], MATERIALS, LIGHTS, camera={"width": 96, "height": 64, "near": 2.0})
    expected, depth = closed_form_faces(scene, [WALL["vertices"], FLOOR["vertices"]])
    _, faces = render_zbuffer(scene, return_faces=True)
    sure = expected != -2
    assert (faces[..., 0] == expected)[sure].all()
    assert ((expected >= 0) & (depth < 2.0)).sum() > 500  # the case under test: visible, nearer than d_f
    assert (expected == 0).sum() > 500 and (expected == 1).sum() > 500
    assert (~sure).sum() < 0.02 * sure.size


def test_triangle_behind_the_eye_is_not_drawn():
    """A naive perspective divide by the negative depth would mirror this triangle onto the image."""
    behind = {"shape": "triangles", "vertices": [[-3.0, -2.0, 8.0], [3.0, -2.0, 8.0], [0.0, 3.0, 8.0]], "faces": [[0, 1, 2]],
              "material": "wall"}
    scene = make_scene([behind], MATERIALS, LIGHTS, camera={"width": 48, "height": 32}, background=[0.1, 0.2, 0.3])
    result, faces = render_zbuffer(scene, return_faces=True)
    assert (faces == -1).all()
    assert np.allclose(result.image, [0.1, 0.2, 0.3])


def test_no_cracks_around_a_vertex_on_a_pixel_centre():
    """Eight coplanar triangles around a vertex that projects onto a pixel centre, with edges along the
    middle row, middle column and both diagonals: every sample inside the square is covered by one
    of them (top-left rule, edges evaluated from one canonical end), and none outside it."""
    ring = [[1, 0], [1, 1], [0, 1], [-1, 1], [-1, 0], [-1, -1], [0, -1], [1, -1]]
    vertices = [[0.0, 0.0, 0.0]] + [[x, y, 0.0] for x, y in ring]
    faces = [[0, 1 + i, 1 + (i + 1) % 8] for i in range(8)]
    fan = {"shape": "triangles", "vertices": vertices, "faces": faces, "material": "wall"}
    # Odd sizes put the image centre on a pixel centre; square pixels put the diagonals through pixel centres too.
    scene = make_scene([fan], MATERIALS, LIGHTS, camera={"width": 65, "height": 65, "fovy": 90.0})
    _, faces_seen = render_zbuffer(scene, return_faces=True)
    b = pinhole(scene.camera)
    d = pixel_directions(b)
    hit = b.eye + d * (5.0 / b.d_f)  # every ray meets z = 0 at depth 5
    inside = (np.abs(hit[..., 0]) < 1 - MARGIN) & (np.abs(hit[..., 1]) < 1 - MARGIN)
    outside = (np.abs(hit[..., 0]) > 1 + MARGIN) | (np.abs(hit[..., 1]) > 1 + MARGIN)
    on_edges = inside & ((np.abs(hit[..., 0]) < 1e-9) | (np.abs(hit[..., 1]) < 1e-9)
                         | (np.abs(np.abs(hit[..., 0]) - np.abs(hit[..., 1])) < 1e-9))
    assert on_edges.sum() >= 4 * 12  # the case under test: many samples exactly on shared edges
    assert (faces_seen[..., 0][inside] >= 0).all()
    assert (faces_seen[..., 0][outside] == -1).all()
