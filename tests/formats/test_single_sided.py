"""glTF's doubleSided, against closed forms: a material that is not double-sided (the specification's
default) is invisible from behind to camera, reflection and refraction rays, and still casts shadows.
A glTF quad of base colour Q before a backdrop of colour B, C_amb = 1 and no lights: a pixel is the
ka of what its ray meets, so where the ray crosses the quad from behind it is B, from the front Q."""

import numpy as np
import pytest

import warprt
from oracle import camera_rays, ray_plane

from formats.gltf_files import Gltf, quaternion
from scenekit import write_scene

Q = (0.9, 0.2, 0.1)  # the quad's base colour
B = (0.1, 0.3, 0.8)  # the backdrop's ka
QUAD = [[-1.0, -1.0, 0.0], [1.0, -1.0, 0.0], [1.0, 1.0, 0.0], [-1.0, 1.0, 0.0]]  # facing +z by its winding
EDGE = 0.02  # pixels whose ray passes this close to the quad's edge are left out (not a sidedness question)


def quad_gltf(path, double_sided=None, material=True, **node):
    """The quad as an exporter writes it; double_sided=None leaves doubleSided out (glTF's default: false);
    material=False gives the primitive no material (the specification's default material, also single-sided)."""
    g = Gltf()
    m = None
    if material:
        fields = {"pbrMetallicRoughness": {"baseColorFactor": [*Q, 1.0]}}
        if double_sided is not None:
            fields["doubleSided"] = double_sided
        m = g.add("materials", fields)
    g.node(mesh=g.mesh(QUAD, [[0, 1, 2], [0, 2, 3]], material=m), **node)
    return g.write(path)


def quad_doc(eye, backdrop_z, backdrop, size=64, lights=(), **render):
    """The scene-file dict of the quad q.gltf at the origin before a backdrop (material ``backdrop``,
    double-sided, as scene files' materials are) in the plane z = backdrop_z, seen from ``eye`` looking
    at the origin with a ``size`` x ``size`` image."""
    doc = {
        "camera": {"eye": list(eye), "center": [0.0, 0.0, 0.0], "fovy": 60.0, "width": size, "height": size},
        "render": dict(render),
        "materials": {"backdrop": dict(backdrop)},
        "objects": [{"mesh": "q.gltf"},
                    {"shape": "plane", "size": [20.0, 20.0], "rotate": [90.0, 0.0, 0.0],
                     "translate": [0.0, 0.0, backdrop_z], "material": "backdrop"}],
    }
    if lights:
        doc["lights"] = [dict(l) for l in lights]
    return doc


# A mirror at 45 degrees about the origin (normal (1, 0, 1)/sqrt 2), and the backdrop's material in the
# plane x = 6, facing it.
MIRROR_PLANE = {"shape": "plane", "size": [3.0, 3.0], "rotate": [90.0, 45.0, 0.0], "material": "mirror"}
SIDE_BACKDROP = {"shape": "plane", "size": [20.0, 20.0], "rotate": [0.0, 0.0, 90.0], "translate": [6.0, 0.0, 0.0],
                 "material": "backdrop"}


def scene_toml(tmp_path, camera_z, backdrop_z, materials=None, objects=()):
    """The camera on the z axis at camera_z looking at the quad, the backdrop (double-sided, as scene
    files' materials are) in the plane z = backdrop_z; ``materials`` and ``objects`` added after."""
    doc = quad_doc([0.0, 0.0, camera_z], backdrop_z, {"ka": list(B), "kd": [0.0, 0.0, 0.0]},
                   ambient=[1.0, 1.0, 1.0], max_depth=1)
    doc["materials"].update(materials or {})
    doc["objects"] += [dict(o) for o in objects]
    return warprt.load_scene(write_scene(tmp_path, doc, "s.toml"))


def quad_pixels(scene):
    """Where the camera rays cross the quad well inside its edges, and where they miss it well outside."""
    eye, d = camera_rays(scene.camera)
    p = eye + ray_plane(eye, d, np.zeros(3), [0.0, 0.0, 1.0])[..., None] * d
    reach = np.abs(p[..., :2]).max(-1)
    return reach < 1.0 - EDGE, reach > 1.0 + EDGE


def assert_sees(image, where, colour, least=300):
    assert where.sum() >= least
    np.testing.assert_allclose(image[where], np.broadcast_to(colour, image[where].shape), atol=1e-6)


def view(tmp_path, side, **quad):
    """The scene with the quad written as ``quad`` says, seen from ``side``: "front" (+z) or "behind"."""
    quad_gltf(tmp_path / "q.gltf", **quad)
    return scene_toml(tmp_path, 4.0, -2.0) if side == "front" else scene_toml(tmp_path, -4.0, 2.0)


@pytest.mark.parametrize("quad", [{}, {"double_sided": False}, {"material": False}],
                         ids=["doubleSided absent", "doubleSided false", "no material"])
def test_a_single_sided_quad_seen_from_behind_shows_the_backdrop_at_every_pixel(tmp_path, quad):
    scene = view(tmp_path, "behind", **quad)
    image = warprt.render(scene).image
    on, off = quad_pixels(scene)
    assert_sees(image, on, B)
    assert_sees(image, off, B)


def test_a_single_sided_quad_seen_from_the_front_is_drawn(tmp_path):
    scene = view(tmp_path, "front")
    image = warprt.render(scene).image
    on, off = quad_pixels(scene)
    assert_sees(image, on, Q)
    assert_sees(image, off, B)


def test_a_double_sided_quad_is_drawn_from_behind_and_fails_the_culling_check(tmp_path):
    """The control: doubleSided true, culling off, draws the quad from behind, and the from-behind
    check of the tests above fails on that image (it can tell)."""
    scene = view(tmp_path, "behind", double_sided=True)
    image = warprt.render(scene).image
    on, _ = quad_pixels(scene)
    assert_sees(image, on, Q)
    with pytest.raises(AssertionError):
        assert_sees(image, on, B)


def test_a_node_turned_around_turns_its_faces(tmp_path):
    """Seen from the front camera, the quad's node turned half a turn about y shows its back: culled."""
    quad_gltf(tmp_path / "q.gltf", rotation=quaternion([0.0, 1.0, 0.0], 180.0))
    scene = scene_toml(tmp_path, 4.0, -2.0)
    on, _ = quad_pixels(scene)
    assert_sees(warprt.render(scene).image, on, B)


def mirror_scene(tmp_path, double_sided):
    """A mirror at 45 degrees (normal (1, 0, 1)/sqrt 2) sends the camera's rays along +x onto the quad
    in the plane x = 3, whose winding faces +x: away from them; the backdrop lies beyond, at x = 6."""
    quad_gltf(tmp_path / "q.gltf", double_sided=double_sided, rotation=quaternion([0.0, 1.0, 0.0], 90.0),
              translation=[3.0, 0.0, 0.0])
    return scene_toml(tmp_path, 4.0, -20.0,
                      {"mirror": {"ka": [0.0, 0.0, 0.0], "kd": [0.0, 0.0, 0.0], "reflectivity": 1.0}},
                      [MIRROR_PLANE, SIDE_BACKDROP]).with_render(max_depth=2)


@pytest.mark.parametrize("double_sided, colour", [(False, B), (True, Q)])
def test_a_mirror_sees_through_the_back_of_a_single_sided_quad(tmp_path, double_sided, colour):
    """Single-sided, the reflection rays pass the quad's back and meet the backdrop; double-sided (the
    control), they stop on the quad."""
    scene = mirror_scene(tmp_path, double_sided)
    n = np.array([1.0, 0.0, 1.0]) / np.sqrt(2.0)
    eye, d = camera_rays(scene.camera)
    p = eye + ray_plane(eye, d, np.zeros(3), n)[..., None] * d
    r = d - 2.0 * (d @ n)[..., None] * n
    q = p + ray_plane(p, r, [3.0, 0.0, 0.0], [1.0, 0.0, 0.0])[..., None] * r
    on_mirror = (np.abs(p[..., 1]) < 1.4) & (np.abs(p @ np.array([1.0, 0.0, -1.0]) / np.sqrt(2.0)) < 1.4)
    seen = on_mirror & (np.abs(q[..., 1:]).max(-1) < 1.0 - EDGE)
    for primary, reflections in (("raytrace", "bvh"), ("zbuffer", "mirrors")):
        assert_sees(warprt.render(scene, primary_query=primary, reflection_query=reflections).image, seen, colour, least=200)


def test_shadow_rays_are_stopped_by_the_back_of_a_single_sided_quad(tmp_path):
    """Shadow rays ignore sidedness: the quad at y = 1 faces up, so the shadow rays from the floor (kd 1,
    normal +y) to the point light without falloff at (0, 5, 0) meet its back, and it still shadows the
    floor. A floor point is lit max(0, n.L) = L_y where the segment to the light misses the quad, else 0."""
    quad_gltf(tmp_path / "q.gltf", rotation=quaternion([1.0, 0.0, 0.0], -90.0), translation=[0.0, 1.0, 0.0])
    doc = {
        "camera": {"eye": [0.0, 3.0, 6.0], "center": [0.0, 0.0, 0.0], "fovy": 60.0, "width": 64, "height": 64},
        "render": {"ambient": [0.0, 0.0, 0.0], "max_depth": 1},
        "lights": [{"position": [0.0, 5.0, 0.0]}],
        "materials": {"floor": {"kd": [1.0, 1.0, 1.0]}},
        "objects": [{"mesh": "q.gltf"}, {"shape": "plane", "size": [20.0, 20.0], "material": "floor"}],
    }
    scene = warprt.load_scene(write_scene(tmp_path, doc, "s.toml"))
    assert scene.materials[scene.objects[0].material].double_sided is False
    up = np.array([0.0, 1.0, 0.0])
    eye, d = camera_rays(scene.camera)
    on_quad = np.abs((eye + ray_plane(eye, d, up, up)[..., None] * d)[..., [0, 2]]).max(-1)  # seen from the front
    t = ray_plane(eye, d, np.zeros(3), up)
    p = eye + np.where(np.isfinite(t), t, 0.0)[..., None] * d
    to_light = np.array([0.0, 5.0, 0.0]) - p
    L = to_light / np.linalg.norm(to_light, axis=-1, keepdims=True)
    with np.errstate(invalid="ignore"):  # rays off the floor: left out below
        crossing = np.abs((p + ray_plane(p, L, up, up)[..., None] * L)[..., [0, 2]]).max(-1)
    floor = (on_quad > 1.0 + EDGE) & np.isfinite(t) & (np.abs(p[..., [0, 2]]).max(-1) < 9.5)  # on the 20 x 20 floor
    shadowed, lit = floor & (crossing < 1.0 - EDGE), floor & (crossing > 1.0 + EDGE)
    image = warprt.render(scene).image
    assert_sees(image, shadowed, (0.0, 0.0, 0.0), least=50)
    np.testing.assert_allclose(image[lit], np.repeat(L[lit][:, 1:2], 3, axis=1), atol=1e-5)


def test_the_plain_zbuffer_culls_as_the_tracer_does(tmp_path):
    for side, colour in (("behind", B), ("front", Q)):
        scene = view(tmp_path, side)
        on, _ = quad_pixels(scene)
        assert_sees(warprt.render(scene, algorithm="zbuffer").image, on, colour)


def test_hybrid_and_virtual_cameras_leave_a_scene_with_culling_to_the_tracer_exactly(tmp_path):
    """Neither the Z-buffer nor the mirrors' virtual cameras know sidedness: asked for, they are not used
    and the image is the traced one to the bit, with the same rays. The control: the same scene
    double-sided uses both."""
    for double_sided in (False, True):
        scene = mirror_scene(tmp_path, double_sided)
        traced = warprt.render(scene, primary_query="raytrace", reflection_query="bvh")
        fast = warprt.render(scene, primary_query="zbuffer", reflection_query="mirrors")
        assert fast.stats.primary_query == ("zbuffer" if double_sided else "raytrace")
        assert fast.stats.reflection_query == ("mirrors" if double_sided else "bvh")
        assert ("C" in traced.stats.variant.split("_")[1]) is not double_sided
        assert np.array_equal(fast.image, traced.image) and fast.stats.rays == traced.stats.rays


def test_doubleSided_that_is_not_a_boolean_is_refused_naming_the_field(tmp_path):
    quad_gltf(tmp_path / "q.gltf", double_sided="yes")
    with pytest.raises(warprt.SceneError, match=r"materials\[0\]\.doubleSided.*expected true or false"):
        warprt.load_scene(tmp_path / "q.gltf")


def test_a_glTF_dielectric_stays_double_sided(tmp_path):
    """KHR_materials_volume: "the doubleSided property has no effect on volume boundaries"; a refracted
    ray leaves glass through its back faces."""
    g = Gltf()
    m = g.add("materials", {"extensions": {"KHR_materials_transmission": {"transmissionFactor": 1.0}}})
    g.node(mesh=g.mesh(QUAD, [[0, 1, 2], [0, 2, 3]], material=m))
    scene = warprt.load_scene(g.write(tmp_path / "g.gltf"))
    (material,) = {scene.materials[o.material] for o in scene.objects}
    assert material.dielectric and material.double_sided


def test_a_scene_files_material_may_be_single_sided(tmp_path):
    """double_sided = false in a scene file culls as glTF does: the wall in z = 0 (a plane turned to face
    -z by its winding) seen from +z shows the backdrop; the default (true) draws it."""
    from tests.scenekit import make_scene

    wall = {"shape": "plane", "size": [2.0, 2.0], "rotate": [-90.0, 0.0, 0.0], "material": "w"}
    back = {"shape": "plane", "size": [20.0, 20.0], "rotate": [90.0, 0.0, 0.0], "translate": [0.0, 0.0, -2.0],
            "material": "b"}
    for double_sided, colour in ((False, B), (True, Q)):
        scene = make_scene([wall, back], {"w": {"ka": list(Q), "kd": [0.0] * 3, "double_sided": double_sided},
                                          "b": {"ka": list(B), "kd": [0.0] * 3}},
                           camera={"eye": [0.0, 0.0, 4.0], "width": 64, "height": 64}, ambient=[1.0] * 3)
        v, f = scene.objects[0].vertices, scene.objects[0].faces[0]
        assert np.cross(v[f[1]] - v[f[0]], v[f[2]] - v[f[0]])[2] < 0  # the winding faces away from the eye
        on, _ = quad_pixels(scene)
        assert_sees(warprt.render(scene).image, on, colour)


@pytest.mark.parametrize("material, message", [
    ({"double_sided": "no"}, "expected true or false, got 'no'"),
    ({"ior": 1.5, "double_sided": False}, "a dielectric (ior) is seen from inside through its back faces"),
])
def test_a_bad_double_sided_is_one_error_naming_the_field(material, message):
    from tests.scenekit import make_scene

    with pytest.raises(warprt.SceneError) as e:
        warprt.render(make_scene([{"shape": "box", "material": "m"}], {"m": material}))
    assert e.value.field == "materials.m.double_sided" and message in e.value.message


def test_the_first_hit_aovs_name_what_lies_behind_a_culled_quad(tmp_path):
    """The AOVs record the camera ray's first hit after culling: behind the quad, the backdrop (object 1)
    at its distance from the eye, |p - eye| for p on the plane z = 2, closed form."""
    scene = view(tmp_path, "behind")
    result = warprt.render(scene, aovs=["object", "depth"])
    on, _ = quad_pixels(scene)
    eye, d = camera_rays(scene.camera)
    t = ray_plane(eye, d, [0.0, 0.0, 2.0], [0.0, 0.0, 1.0])
    assert (result.aovs["object"][on] == 1).all()
    np.testing.assert_allclose(result.aovs["depth"][on], t[on], rtol=1e-5)
