"""Glass against closed forms (tests/oracle/optics.py, float64, written from the Fresnel equations and
Snell's law): the kernels' Fresnel and Snell functions, a slab faced squarely (the series of internal
reflections up to max_depth), Snell's angle and the critical angle on single rays, Beer's law through
a cube, exact ray counts by kind, hard shadows behind glass, and the energy a clear sphere loses only
to the paths max_depth cuts off."""

import math

import numpy as np
import pytest
import warp as wp

import warprt
from oracle import optics
from scenekit import make_scene
from warprt.kernels import fresnel_dielectric, init_warp, refract

ETA = 1.5
CLEAR = {"ior": ETA, "ka": [0.0] * 3, "kd": [0.0] * 3}
LOOK_DOWN_Z = {"eye": [0.0, 0.0, 0.0], "center": [0.0, 0.0, -1.0], "up": [0.0, 1.0, 0.0]}
SLAB_THICKNESS = 0.25


def slab(rotate_y=0.0, thickness=SLAB_THICKNESS, z=-2.0):
    """A glass slab 40 x 40 across, its faces normal to z turned by rotate_y about y, centred at z."""
    return {"shape": "box", "size": [40.0, 40.0, thickness], "rotate": [0.0, rotate_y, 0.0], "translate": [0.0, 0.0, z],
            "material": "glass"}


def panel(x_lo, x_hi, material, z=-6.0):
    """An ambient-only wall facing +z at depth z, spanning x_lo..x_hi (and y -20..20)."""
    return {"shape": "plane", "size": [x_hi - x_lo, 40.0], "rotate": [90.0, 0.0, 0.0],
            "translate": [(x_lo + x_hi) / 2.0, 0.0, z], "material": material}


# --- the kernels' functions ---------------------------------------------------------------------------

@wp.kernel
def fresnel_kernel(cos_i: wp.array(dtype=float), eta: float, out: wp.array(dtype=float)):
    i = wp.tid()
    out[i] = fresnel_dielectric(cos_i[i], eta)


@wp.kernel
def refract_kernel(d: wp.array(dtype=wp.vec3), n: wp.array(dtype=wp.vec3), eta: float,
                   t: wp.array(dtype=wp.vec3), ok: wp.array(dtype=int)):
    i = wp.tid()
    direction, transmits = refract(d[i], n[i], eta)
    t[i] = direction
    ok[i] = wp.where(transmits, 1, 0)


def warp_fresnel(cos_i, eta):
    init_warp()
    c = wp.array(np.asarray(cos_i, np.float32), dtype=float)
    out = wp.empty(len(c), dtype=float)
    wp.launch(fresnel_kernel, dim=len(c), inputs=[c, float(eta), out])
    return out.numpy().astype(np.float64)


@pytest.mark.parametrize("eta", [1.33, 1.5, 2.42])
def test_fresnel_matches_the_closed_form_at_every_angle_from_both_sides(eta):
    """F from outside (cos_i > 0, into eta) and from inside (cos_i < 0, into air), against
    (r_s^2 + r_p^2) / 2 in float64; 1 past the critical angle; ((eta - 1)/(eta + 1))^2 head on."""
    cos_i = np.linspace(-1.0, 1.0, 4001).astype(np.float32).astype(np.float64)
    got = warp_fresnel(cos_i, eta)
    expect = np.where(cos_i >= 0, optics.fresnel(cos_i, 1.0, eta), optics.fresnel(cos_i, eta, 1.0))
    # float32 loses digits where cos_t -> 0, just inside the critical angle: compare away from it.
    rel = np.where(cos_i >= 0, 1.0 / eta, eta)
    cos_t2 = 1.0 - rel**2 * (1.0 - cos_i**2)
    away = np.abs(cos_t2) > 1e-2
    assert np.abs(got - expect)[away].max() < 2e-6
    assert (got[cos_t2 < 0] == 1.0).all() and (cos_t2 < 0).sum() > 100  # total internal reflection
    head_on = warp_fresnel([1.0, -1.0], eta)
    assert np.allclose(head_on, optics.normal_incidence(eta), rtol=1e-6, atol=0)


def test_refract_obeys_snells_law_and_agrees_with_fresnel_on_total_internal_reflection():
    rng = np.random.default_rng(7)
    n = rng.normal(size=(20000, 3))
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    d = rng.normal(size=(20000, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    d = np.where(np.sum(d * n, 1)[:, None] > 0, -d, d)  # arriving: d.n < 0
    init_warp()
    for eta in (ETA, 1.0 / ETA):
        t, ok = wp.empty(len(d), dtype=wp.vec3), wp.empty(len(d), dtype=int)
        wp.launch(refract_kernel, dim=len(d), inputs=[wp.array(d.astype(np.float32), dtype=wp.vec3),
                                                      wp.array(n.astype(np.float32), dtype=wp.vec3), eta, t, ok])
        t, ok = t.numpy().astype(np.float64), ok.numpy().astype(bool)
        cos_i = -np.sum(d * n, 1)
        sin_i = np.sqrt(np.maximum(0.0, 1.0 - cos_i**2))
        exists = sin_i / eta < 1.0
        clear = np.abs(sin_i / eta - 1.0) > 1e-4
        assert np.array_equal(ok[clear], exists[clear])
        tt = t[ok] / np.linalg.norm(t[ok], axis=1, keepdims=True)
        sin_t = np.linalg.norm(np.cross(tt, n[ok]), axis=1)
        assert np.abs(sin_t - sin_i[ok] / eta).max() < 1e-5  # Snell
        assert (np.sum(tt * n[ok], 1) < 0).all()  # onward, through the surface
        assert np.abs(np.sum(np.cross(d[ok], n[ok]) * tt, 1)).max() < 1e-5  # in the plane of incidence
        F = warp_fresnel(np.where(eta > 1.0, cos_i, -cos_i), ETA)
        assert np.array_equal(F == 1.0, ~ok)  # both see total internal reflection on the same rays


# --- a slab and a cube faced squarely -------------------------------------------------------------------

SLAB_GLASS = {**CLEAR, "transmittance": 0.9, "absorption": [0.4, 0.2, 0.8]}


@pytest.mark.parametrize("max_depth", [2, 3, 4, 5, 8, 24])
def test_normal_incidence_through_a_slab_is_the_series_of_internal_reflections(max_depth):
    """Behind the slab an ambient-only wall (red and green 1), in front nothing (background blue 1):
    red and green are the light through, T = sum_n (1-F)^2 k_t^2 F^(2n) a^(2n+1), blue the light back,
    R = F + sum_n (1-F)^2 k_t^2 F^(2n+1) a^(2n+2), each path kept while it fits in max_depth levels;
    F = ((eta-1)/(eta+1))^2 per interface, a = exp(-sigma d)."""
    scene = make_scene([slab(), panel(-20.0, 20.0, "wall")], {"glass": SLAB_GLASS, "wall": {"ka": [1.0, 1.0, 0.0], "kd": [0.0] * 3}},
                       camera={**LOOK_DOWN_Z, "fovy": 2.0, "width": 5, "height": 5},
                       ambient=[1.0] * 3, background=[0.0, 0.0, 1.0], max_depth=max_depth)
    image, stats = warprt.render(scene)
    T, R, _ = optics.slab_series(0.0, ETA, SLAB_GLASS["transmittance"], SLAB_GLASS["absorption"], SLAB_THICKNESS, max_depth)
    assert np.allclose(image[2, 2], [T[0], T[1], R[2]], rtol=2e-6, atol=1e-7)


@pytest.mark.parametrize("max_depth", [3, 24])
def test_beer_attenuation_through_a_cube_of_known_thickness(max_depth):
    """An absorbing cube of side L faced squarely in front of nothing: the pixel is the background
    times the slab series with a = exp(-sigma L); at three levels B (F + (1 - F)^2 exp(-sigma L))."""
    side, sigma, background = 1.3, [0.9, 0.3, 0.05], np.array([0.6, 0.7, 0.8])
    cube = {"shape": "box", "size": side, "translate": [0.0, 0.0, -3.0], "material": "glass"}
    scene = make_scene([cube], {"glass": {**CLEAR, "absorption": sigma}}, camera={**LOOK_DOWN_Z, "fovy": 2.0, "width": 5, "height": 5},
                       background=background.tolist(), max_depth=max_depth)
    image, _ = warprt.render(scene)
    T, R, _ = optics.slab_series(0.0, ETA, 1.0, sigma, side, max_depth)
    assert np.allclose(image[2, 2], background * (T + R), rtol=2e-6, atol=1e-7)
    if max_depth == 3:
        F = optics.normal_incidence(ETA)
        assert np.allclose(image[2, 2], background * (F + (1 - F) ** 2 * np.exp(-np.asarray(sigma) * side)), rtol=2e-6)


# --- Snell's angle and the critical angle on single rays -------------------------------------------------

@pytest.mark.parametrize("theta", [10.0, 30.0, 50.0, 70.0])
def test_a_ray_through_a_tilted_slab_leaves_parallel_shifted_by_snells_law(theta):
    """The slab turned by theta about y: the centre ray leaves it parallel to itself, shifted sideways
    by d sin(theta - theta_t) / cos(theta_t) (Snell: sin theta = eta sin theta_t), and lands on the wall
    behind at the closed form's x. A wall whose colour changes 1e-3 past that point, on either side,
    shows the colour of the side the ray lands on, weighted by (1-F)^2 k_t^2 exp(-sigma d / cos theta_t)."""
    front, back = tilted_slab_faces(theta)
    w, o, d, _ = optics.plane_path(np.zeros(3), np.array([0.0, 0.0, -1.0]), [(front, "T"), (back, "T")],
                                   ETA, SLAB_GLASS["transmittance"], SLAB_GLASS["absorption"])
    assert np.allclose(d, [0.0, 0.0, -1.0])
    theta_t = float(optics.snell_angle(math.radians(theta), 1.0, ETA))
    shift = SLAB_THICKNESS * math.sin(math.radians(theta) - theta_t) / math.cos(theta_t)
    x_land = o[0] + (-6.0 - o[2]) / d[2] * d[0]
    assert abs(abs(x_land) - shift) < 1e-12 and shift > 0.004
    F = optics.fresnel(math.cos(math.radians(theta)), 1.0, ETA)
    a = np.exp(-np.asarray(SLAB_GLASS["absorption"]) * SLAB_THICKNESS / math.cos(theta_t))
    assert np.allclose(w, (1 - F) ** 2 * SLAB_GLASS["transmittance"] ** 2 * a)
    for edge, lands_on in ((x_land + 1e-3, "left"), (x_land - 1e-3, "right")):
        # Walls 2 wide: the light the slab's front reflects at 50 and 70 degrees passes beside them.
        scene = make_scene([slab(theta), panel(-1.0, edge, "left"), panel(edge, 1.0, "right")],
                           {"glass": SLAB_GLASS, "left": {"ka": [1.0, 0.0, 0.0], "kd": [0.0] * 3},
                            "right": {"ka": [0.0, 1.0, 0.0], "kd": [0.0] * 3}},
                           camera={**LOOK_DOWN_Z, "fovy": 1.0, "width": 1, "height": 1}, ambient=[1.0] * 3, max_depth=3)
        pixel = warprt.render(scene).image[0, 0]
        channel = 0 if lands_on == "left" else 1
        assert pixel[1 - channel] == 0.0
        # The refracted ray starts past the hit point's error bound, about 1e-4 off the face for these
        # 40-unit triangles, so the segment inside is up to that times sin^2/cos shorter: sigma 1e-4 at most.
        assert abs(pixel[channel] - w[channel]) < 1e-4 * w[channel]


def tilted_slab_faces(theta):
    """The front and back faces of slab(theta) as closed-form planes with outward normals."""
    a = math.radians(theta)
    n, u, v = np.array([math.sin(a), 0.0, math.cos(a)]), np.array([math.cos(a), 0.0, -math.sin(a)]), np.array([0.0, 1.0, 0.0])
    c, h, s = np.array([0.0, 0.0, -2.0]), SLAB_THICKNESS / 2, 20.0
    quad = lambda cc, uu: [cc - s * uu - s * v, cc + s * uu - s * v, cc + s * uu + s * v, cc - s * uu + s * v]
    return optics.Face(quad(c + h * n, u), n), optics.Face(quad(c - h * n, -u), -n)


def inside_glass_looking_up(theta, max_depth=2, width=1, fovy=1.0):
    """The eye inside a large glass box, looking at its top face at theta degrees from the face's
    normal; background 1."""
    box = {"shape": "box", "size": [1000.0, 4.0, 1000.0], "material": "glass"}
    a = math.radians(theta)
    camera = {"eye": [0.0, 0.0, 0.0], "center": [0.0, math.cos(a), -math.sin(a)], "up": [0.0, 0.0, -1.0] if theta < 1 else [0.0, 1.0, 0.0],
              "fovy": fovy, "width": width, "height": width}
    return make_scene([box], {"glass": CLEAR}, camera=camera, background=[1.0] * 3, max_depth=max_depth)


@pytest.mark.parametrize("side", [-0.5, 0.5])
def test_total_internal_reflection_past_the_critical_angle(side):
    """From inside, asin(1/eta) = 41.81 degrees from the normal: half a degree before it the ray gets out
    with weight 1 - F (and F reflected back in); half a degree past it nothing gets out."""
    theta = math.degrees(optics.critical_angle(ETA)) + side
    image, stats = warprt.render(inside_glass_looking_up(theta))
    assert stats.rays["reflection"] == 1
    if side < 0:
        assert stats.rays["refraction"] == 1
        F = optics.fresnel(math.cos(math.radians(theta)), ETA, 1.0)
        assert F < 1.0 and np.allclose(image[0, 0], 1.0 - F, rtol=1e-4)
    else:
        assert stats.rays["refraction"] == 0 and (image == 0.0).all()


# --- exact ray counts ------------------------------------------------------------------------------------

@pytest.mark.parametrize("max_depth", [1, 2, 3, 6])
def test_a_slab_filling_the_view_spawns_one_reflected_and_one_refracted_ray_per_level(max_depth):
    """Every level past the first has one ray that leaves the slab (a miss) and one that goes on
    inside it: (max_depth - 1) reflection and refraction rays per pixel, no shadow rays without lights."""
    W, H = 8, 6
    scene = make_scene([slab()], {"glass": CLEAR}, camera={**LOOK_DOWN_Z, "fovy": 10.0, "width": W, "height": H},
                       background=[1.0] * 3, max_depth=max_depth)
    rays = warprt.render(scene).stats.rays
    assert rays == {"primary": W * H, "shadow": 0, "reflection": (max_depth - 1) * W * H,
                    "refraction": (max_depth - 1) * W * H, "total": (2 * max_depth - 1) * W * H}


@pytest.mark.parametrize("max_depth", [2, 5])
def test_rays_trapped_by_total_internal_reflection_spawn_no_refraction_ray(max_depth):
    """Inside glass, 55 to 65 degrees from the faces' normals: every hit reflects totally, back and forth
    between the top and bottom faces, one reflection ray per level and no refracted ray."""
    W = 6
    rays = warprt.render(inside_glass_looking_up(60.0, max_depth, width=W, fovy=10.0)).stats.rays
    assert rays == {"primary": W * W, "shadow": 0, "reflection": (max_depth - 1) * W * W, "refraction": 0,
                    "total": max_depth * W * W}


# --- shadows and energy ----------------------------------------------------------------------------------

def test_glass_casts_a_hard_shadow_like_any_surface():
    """A glass pane between a point light and a wall, seen through the pane head on: the wall behind it
    gets the ambient term only, (1 - F)^2 C_amb ka through the pane's two faces, as it would behind an
    opaque pane (Whitted's model, and Mitsuba's direct lighting from a point light behind glass)."""
    wall = {"kd": [0.8, 0.6, 0.4], "ka": [0.1, 0.1, 0.1]}
    objects = [panel(-20.0, 20.0, "wall", z=0.0),
               {"shape": "box", "size": [6.0, 6.0, 0.1], "translate": [0.0, 0.0, 2.0], "material": "glass"}]
    camera = {"eye": [0.0, 0.0, 10.0], "center": [0.0, 0.0, 0.0], "fovy": 10.0, "width": 9, "height": 9}
    scene = make_scene(objects, {"wall": wall, "glass": CLEAR}, [{"position": [0.0, 0.0, 6.0]}], camera=camera,
                       ambient=[1.0] * 3, max_depth=3)
    r = warprt.render(scene)
    F = optics.normal_incidence(ETA)
    assert np.allclose(r.image[4, 4], (1 - F) ** 2 * np.asarray(wall["ka"]), rtol=1e-5)


def test_a_clear_sphere_loses_energy_only_to_the_paths_max_depth_cuts_off():
    """The furnace: a clear glass sphere (no local terms, no lights, ambient 0) before a constant
    background B. Fresnel splits each ray's weight without loss, so every pixel is B times the weight
    that got out, and B minus it is B times the weight of the truncated paths, which shrinks with
    max_depth until the sphere all but disappears."""
    B = np.array([0.5, 0.5, 0.5])
    sphere = {"shape": "sphere", "radius": 1.0, "subdivisions": 3, "smooth": True, "material": "glass"}
    mean = {}
    for max_depth in (2, 4, 8, 16):
        scene = make_scene([sphere], {"glass": CLEAR}, camera={"eye": [0.0, 0.0, 3.5], "fovy": 40.0, "width": 24, "height": 24},
                           background=B.tolist(), max_depth=max_depth)
        r = warprt.render(scene, report_truncated=True)
        assert np.abs(r.image + B * r.stats.truncated - B).max() < 2e-6
        assert r.stats.to_dict()["truncated"]["max"] == pytest.approx(float(r.stats.truncated.max()))
        mean[max_depth] = float(r.stats.truncated.mean())
    assert mean[2] > mean[4] > mean[8] > mean[16]
    assert mean[16] < 1e-3 < mean[2]
