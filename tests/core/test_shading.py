"""Each Phong term, shadows and mirror reflection on cases with closed-form answers."""

import numpy as np
import pytest

import warprt
from scenekit import MARKER, make_scene
from oracle import camera_rays, phong_terms, ray_plane, ray_sphere_distance

C_AMB = np.array([0.1, 0.2, 0.3])
C_L = np.array([0.9, 0.8, 0.7])
LIGHT = np.array([1.0, 2.0, 3.0])
MAT = {"ka": [0.2, 0.1, 0.05], "kd": [0.5, 0.6, 0.7], "ks": [0.3, 0.4, 0.5], "shininess": 20.0}
WALL = {"shape": "plane", "size": [20.0, 20.0], "rotate": [90.0, 0.0, 0.0], "material": "m"}  # z = 0, facing +z


def wall_scene(**render):
    return make_scene([WALL], {"m": MAT}, [{"position": LIGHT.tolist(), "color": C_L.tolist()}],
                      ambient=C_AMB.tolist(), **render)


def wall_terms(scene):
    """The seed's model at every pixel's hit on the plane z = 0, in float64."""
    o, d = camera_rays(scene.camera)
    t = ray_plane(o, d, [0, 0, 0], [0.0, 0.0, 1.0])
    p = o + t[..., None] * d
    return phong_terms(p, np.array([0.0, 0.0, 1.0]), -d, [(LIGHT, C_L)], MAT, C_AMB)


@pytest.mark.parametrize("terms", [["ambient"], ["diffuse"], ["specular"], ["ambient", "diffuse", "specular"]])
def test_phong_terms_closed_form(terms):
    scene = wall_scene(shadows=False)
    image, _ = warprt.render(scene, effects=terms)
    expect = sum(wall_terms(scene)[t] for t in terms)
    # float32 geometry and arithmetic against float64: relative 1e-4 covers it, a wrong term does not pass.
    np.testing.assert_allclose(image, expect, rtol=2e-4, atol=2e-6)
    assert expect.max() > 0.01


def test_specular_highlight_is_where_r_meets_v():
    """The brightest specular pixel is the mirror point of the light as seen from the eye."""
    scene = wall_scene(shadows=False)
    image, _ = warprt.render(scene, effects=["specular"])
    expect = wall_terms(scene)["specular"]
    assert np.unravel_index(image[..., 0].argmax(), image.shape[:2]) == np.unravel_index(expect[..., 0].argmax(), expect.shape[:2])


def test_shadow_leaves_exactly_the_ambient_term():
    """A square occluder between the light and the wall: where the segment from the wall point to
    the light crosses it, only C_amb ka remains; elsewhere the full Phong value."""
    light = np.array([0.0, 0.0, 4.0])
    occluder = {"shape": "plane", "size": [1.0, 1.0], "rotate": [90.0, 0.0, 0.0], "translate": [0.2, 0.1, 2.0], "material": "m"}
    scene = make_scene([WALL, occluder], {"m": MAT}, [{"position": light.tolist(), "color": C_L.tolist()}],
                       ambient=C_AMB.tolist(), camera={"eye": [0.0, 0.0, 8.0], "width": 80, "height": 80})
    image, stats = warprt.render(scene)
    o, d = camera_rays(scene.camera)
    t_wall = ray_plane(o, d, [0, 0, 0], np.array([0.0, 0.0, 1.0]))
    p = o + t_wall[..., None] * d
    # Where the segment p -> light crosses z = 2, and whether that is inside the occluder square.
    s = (2.0 - p[..., 2]) / (light[2] - p[..., 2])
    cross = p + s[..., None] * (light - p)
    dx, dy = np.abs(cross[..., 0] - 0.2), np.abs(cross[..., 1] - 0.1)
    # Pixels that see the occluder itself are excluded; so are pixels within 1e-3 of the shadow edge.
    t_occ = ray_plane(o, d, [0, 0, 2.0], np.array([0.0, 0.0, 1.0]))
    q = o + t_occ[..., None] * d
    sees_occluder = (np.abs(q[..., 0] - 0.2) <= 0.5 + 1e-3) & (np.abs(q[..., 1] - 0.1) <= 0.5 + 1e-3)
    inside = (np.maximum(dx, dy) < 0.5 - 1e-3) & ~sees_occluder
    outside = (np.maximum(dx, dy) > 0.5 + 1e-3) & ~sees_occluder
    assert inside.sum() > 50 and outside.sum() > 1000
    ambient = np.float32(C_AMB) * np.float32(MAT["ka"])
    np.testing.assert_array_equal(image[inside], np.broadcast_to(ambient, image[inside].shape))
    assert (image[outside] > ambient + 1e-3).all()


def test_mirror_shows_the_reflected_object_at_the_mirrored_position():
    """A mirror floor y = 0 (k_r = 0.5, nothing else) under a marker sphere centred at (0, 1, 0):
    the mirror shows it where the camera ray, continued through the floor, meets the sphere's
    mirror image centred at (0, -1, 0). With one ray level the mirror shows nothing."""
    objects = [
        {"shape": "plane", "size": [40.0, 40.0], "material": "mirror"},
        {"shape": "sphere", "radius": 0.5, "subdivisions": 4, "translate": [0.0, 1.0, 0.0], "material": "marker"},
    ]
    mats = {"mirror": {"ka": [0, 0, 0], "kd": [0, 0, 0], "reflectivity": [0.5, 0.25, 0.125]}, "marker": MARKER}
    camera = {"eye": [0.0, 1.2, 5.0], "center": [0.0, 0.3, 0.0], "width": 64, "height": 64}
    scene = make_scene(objects, mats, ambient=[1.0, 1.0, 1.0], camera=camera, max_depth=2)
    image, stats = warprt.render(scene)
    o, d = camera_rays(scene.camera)
    t_floor = ray_plane(o, d, [0, 0, 0], np.array([0.0, 1.0, 0.0]))
    dist_real, _ = ray_sphere_distance(o, d, np.array([0.0, 1.0, 0.0]))
    dist_image, t_image = ray_sphere_distance(o, d, np.array([0.0, -1.0, 0.0]))
    on_floor = np.isfinite(t_floor) & (dist_real > 0.5)
    shows = on_floor & (dist_image < 0.5 * 0.995)
    misses = on_floor & (dist_image > 0.5)
    assert shows.sum() > 30 and misses.sum() > 500
    np.testing.assert_array_equal(image[shows], np.broadcast_to(np.float32([0.5, 0.25, 0.125]), image[shows].shape))
    np.testing.assert_array_equal(image[misses], 0.0)
    # The sphere seen directly is exactly its marker colour.
    direct = dist_real < 0.5 * 0.995
    np.testing.assert_array_equal(image[direct], 1.0)

    image1, stats1 = warprt.render(scene.with_render(max_depth=1))
    np.testing.assert_array_equal(image1[shows | misses], 0.0)
    assert stats1.rays["reflection"] == 0
