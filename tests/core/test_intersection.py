"""Nearest-hit visibility: hit and miss pixels where closed-form geometry says they are.

An ambient-only marker material with C_amb = 1 makes a hit pixel exactly ka and a miss exactly
the background, so the image is a visibility mask."""

import numpy as np

import warprt
from scenekit import MARKER, make_scene
from oracle import camera_rays, ray_sphere_distance, ray_triangle

ONE = [1.0, 1.0, 1.0]


def mask(scene):
    image, _ = warprt.render(scene, threads=2)
    assert set(np.unique(image)) <= {0.0, 1.0}, "a marker render has only hit (1) and miss (0) pixels"
    return image[..., 0] == 1.0


def test_single_triangle():
    tri = [[-1.5, -1.0, 0.0], [1.7, -0.6, -0.5], [0.2, 1.4, 0.3]]
    scene = make_scene([{"shape": "triangles", "vertices": tri, "faces": [[0, 1, 2]], "material": "m"}],
                       {"m": MARKER}, ambient=ONE)
    hit = mask(scene)
    o, d = camera_rays(scene.camera)
    h = ray_triangle(o, d, *tri)
    clear = np.abs(h.margin) > 1e-4  # pixels whose centre ray is not within float noise of an edge
    assert clear.mean() > 0.99
    np.testing.assert_array_equal(hit[clear], h.hit[clear])
    assert 0.03 < hit.mean() < 0.6  # the oracle has something to say on both sides


def test_quad_both_triangles_and_no_gap():
    # A unit-square plane turned to face the camera, split along its diagonal.
    scene = make_scene([{"shape": "plane", "size": [2.0, 2.0], "rotate": [90.0, 0.0, 0.0], "material": "m"}],
                       {"m": MARKER}, ambient=ONE)
    hit = mask(scene)
    o, d = camera_rays(scene.camera)
    a, b, c, e = (np.array(p, float) for p in ([-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]))
    h1, h2 = ray_triangle(o, d, a, b, c), ray_triangle(o, d, a, c, e)
    m1, m2 = h1.margin, h2.margin
    inside = h1.hit | h2.hit
    # Only the outer boundary is uncertain: the shared diagonal must never leak.
    outer = np.maximum(np.minimum(m1, 1), np.minimum(m2, 1))
    clear = (np.abs(outer) > 1e-4) | ((m1 > -1e-4) & (m2 > -1e-4))
    np.testing.assert_array_equal(hit[clear], inside[clear])
    assert hit.sum() == inside.sum()


def test_sphere_silhouette():
    """The icosphere lies between its inscribed radius and its circumradius 1: rays passing
    nearer the centre than the inscribed radius hit, rays passing farther than 1 miss."""
    scene = make_scene([{"shape": "sphere", "radius": 1.0, "subdivisions": 4, "translate": [0.3, -0.2, 0.0], "material": "m"}],
                       {"m": MARKER}, ambient=ONE)
    hit = mask(scene)
    o, d = camera_rays(scene.camera)
    dist, _ = ray_sphere_distance(o, d, np.array([0.3, -0.2, 0.0]))
    inscribed = 0.995  # subdivision 4: the face planes lie within 0.3% of the unit sphere
    assert hit[dist < inscribed].all()
    assert not hit[dist > 1.0].any()
    assert (dist < inscribed).sum() > 100


def test_nearest_hit_wins():
    """Two overlapping triangles at different depths: the nearer one's colour is seen."""
    near = {"shape": "plane", "size": [1.0, 1.0], "rotate": [90, 0, 0], "translate": [0, 0, 1.0], "material": "near"}
    far = {"shape": "plane", "size": [3.0, 3.0], "rotate": [90, 0, 0], "material": "far"}
    mats = {"near": {"ka": [1.0, 0.0, 0.0], "kd": [0, 0, 0]}, "far": {"ka": [0.0, 0.0, 1.0], "kd": [0, 0, 0]}}
    for order in ([near, far], [far, near]):
        image, _ = warprt.render(make_scene(order, mats, ambient=ONE))
        o, d = camera_rays(make_scene(order, mats).camera)
        m = ray_triangle(o, d, [-0.5, -0.5, 1.0], [0.5, -0.5, 1.0], [0.5, 0.5, 1.0]).margin
        m2 = ray_triangle(o, d, [-0.5, -0.5, 1.0], [0.5, 0.5, 1.0], [-0.5, 0.5, 1.0]).margin
        in_near = (np.minimum(m, 1) > 1e-4) | (np.minimum(m2, 1) > 1e-4)
        assert in_near.sum() > 20
        np.testing.assert_array_equal(image[in_near], np.tile([1.0, 0.0, 0.0], (in_near.sum(), 1)))
