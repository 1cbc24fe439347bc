"""The tie oracle of compare.py says "tie" for a sample on an edge two triangles share, and for
nothing else: it is checked here on samples whose answer is known from the geometry."""

import numpy as np

from tests.scenekit import make_scene
from tests.zbuffer.compare import classify_ties
from tests.zbuffer.test_agreement import LIGHTS, MATERIALS
from tests.zbuffer.traced import traced_faces
from warprt.geometry import Geometry

RING = [[1, 0], [1, 1], [0, 1], [-1, 1], [-1, 0], [-1, -1], [0, -1], [1, -1]]


def fan_scene():
    """Eight triangles around the origin in z = 0, seen head-on; face i spans ring points i and i + 1,
    so faces 7 and 0 share the edge along +x, which the middle row's pixel centres lie on exactly."""
    vertices = [[0.0, 0.0, 0.0]] + [[x, y, 0.0] for x, y in RING]
    faces = [[0, 1 + i, 1 + (i + 1) % 8] for i in range(8)]
    fan = {"shape": "triangles", "vertices": vertices, "faces": faces, "material": "wall"}
    return make_scene([fan], MATERIALS, LIGHTS, camera={"width": 65, "height": 65, "fovy": 90.0})


def ties_after_swapping(scene, geometry, faces, swaps):
    other = faces.copy()
    for (row, col), face in swaps.items():
        other[row, col, 0] = face
    return classify_ties(scene, geometry, faces, other, 1)


def test_a_sample_on_a_shared_edge_is_a_tie():
    scene = fan_scene()
    geometry = Geometry(scene)
    faces = traced_faces(scene, geometry=geometry)
    middle = 32  # the middle row: y = 0 exactly, on the edge of faces 7 and 0 right of the centre
    col = 38  # x about 0.92: inside the fan
    assert faces[middle, col, 0] in (0, 7)
    swapped = 7 if faces[middle, col, 0] == 0 else 0
    assert ties_after_swapping(scene, geometry, faces, {(middle, col): swapped}).all()


def test_a_sample_inside_one_triangle_is_no_tie():
    scene = fan_scene()
    geometry = Geometry(scene)
    faces = traced_faces(scene, geometry=geometry)
    row, col = 27, 36  # x about 0.6, y about 0.8 (rows count down): inside face 1, off every edge
    assert faces[row, col, 0] == 1
    ties = ties_after_swapping(scene, geometry, faces, {(row, col): 5})  # a triangle the ray misses
    assert not ties.any()
    ties = ties_after_swapping(scene, geometry, faces, {(row, col): -1})  # the background behind
    assert not ties.any()
    assert np.count_nonzero(faces >= 0) > 100
