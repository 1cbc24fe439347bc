"""warprt's image gradients (Renderer.backward) against Mitsuba's AD of the reference's own model: the
reference integrator's material() and local() (reference/mitsuba_whitted.py: its Phong terms, Mitsuba's
emitters' sample_direction, its ray_test shadows) evaluated at Mitsuba's first hits of the camera rays
through the pixel centres, with dr.enable_grad on the tables material() gathers from and on each emitter's
intensity, and dr.backward of the same loss sum(w * image).

Measured: images within 1.3e-6, gradients within 1e-6 relative (float32 both). The control: Mitsuba's
model without its shadows gives other gradients, far outside the tolerance.
"""

from __future__ import annotations

import numpy as np
import pytest

import warprt
from reference import mitsuba_variant
from reference.mitsuba_ad import ad_gradients, backpropagated
from reference.mitsuba_whitted import Switches, mitsuba_scene
from warprt.scene import resolve_effects

from grad.test_first_hit_gradients import HEIGHT, MIRROR_PARAMETERS, PARAMETERS, WIDTH, mirror_scene, scene

pytestmark = pytest.mark.accuracy

REL = 1e-4


def mitsuba_gradients(s, weights, shadows: bool = True) -> tuple[np.ndarray, dict]:
    """Mitsuba's image and its AD gradients of sum(weights * image) by r.params name (materials' colours
    and exponents, summed over their objects' table rows; lights' colours): reference.mitsuba_ad's."""
    return ad_gradients(s, weights, shadows)


@pytest.fixture(scope="module")
def weights():
    return np.random.default_rng(7).random((HEIGHT, WIDTH, 3)).astype(np.float32)


@pytest.fixture(scope="module")
def ours(weights):
    r = warprt.Renderer(scene())
    image = r.render(grad=True).image
    return image, r.backward(weights)


def compared(ours_grads, theirs, parameters=PARAMETERS) -> list[str]:
    names = [n for n in parameters if n in theirs]
    assert len(names) >= 6  # every material colour and exponent and every light colour of the scene
    return [n for n in names
            if not np.allclose(ours_grads[n], theirs[n], rtol=REL, atol=REL * np.abs(theirs[n]).max())]


def test_gradients_equal_mitsubas_ad(ours, weights):
    image, grads = ours
    m_image, m_grads = mitsuba_gradients(scene(), weights)
    assert np.abs(image - m_image).max() < 1e-5  # the same model at the same hits
    assert compared(grads, m_grads) == []


def test_mitsubas_ad_without_shadows_is_not_warprts(ours, weights):
    _, grads = ours
    _, m_grads = mitsuba_gradients(scene(), weights, shadows=False)
    assert {"materials.floor.kd", "lights.0.color", "lights.1.color"} <= set(compared(grads, m_grads))


def mitsuba_vertex_gradients(s, weights, detach: bool = False) -> np.ndarray:
    """Mitsuba's AD of the same loss with respect to the first object's vertex positions: its intersection
    recomputed differentiably at the hit face (the camera ray fixed, the hit sliding over the moved
    triangle); with ``detach`` (RayFlags.DetachShape) the hit does not follow the vertices: the control."""
    mitsuba_variant()
    import drjit as dr
    import mitsuba as mi

    ms = mitsuba_scene(s)
    integ = ms.integrator
    integ.switches = Switches.for_effects(resolve_effects(s), s.render)
    params = mi.traverse(ms.mi_scene)
    key = "object_00000.vertex_positions"
    dr.enable_grad(params[key])
    params.update()
    backpropagated(ms, s, weights, detach)
    return np.array(dr.grad(params[key]), np.float64).reshape(-1, 3)


def test_vertex_gradients_equal_mitsubas_ad(weights):
    from grad.test_first_hit_gradients import floor_scene

    r = warprt.Renderer(floor_scene())
    r.render(grad=True)
    ours = r.backward(weights, wrt=["objects.floor.vertices"])["objects.floor.vertices"]
    theirs = mitsuba_vertex_gradients(floor_scene(), weights)
    np.testing.assert_allclose(ours, theirs, rtol=REL, atol=REL * np.abs(theirs).max())
    detached = mitsuba_vertex_gradients(floor_scene(), weights, detach=True)  # the control
    assert np.abs(detached - ours).max() > 0.1 * np.abs(ours).max()


def mitsuba_object_gradients(s, weights, detach: bool = False, normals: bool = False) -> tuple[np.ndarray, dict]:
    """Mitsuba's image and AD gradients of the same loss with respect to every object's vertex positions
    (mitsuba_vertex_gradients' for each object, by r.params name), through the reference's levels: its
    spawn_ray from the differentiable hit along the direction reflected about its normal. A smooth object's
    normals are Mitsuba's own, recomputed from the positions by params.update() (angle-weighted, as the
    scene's vertex_normals; Mitsuba's AD does not follow them: its gradient holds them fixed), or with
    ``normals``, for the objects whose normals the scene computes from their triangles, the same angle-weighted
    sums written in Dr.Jit over the positions (dr.scatter_reduce), which its AD follows. Gradients cleared
    first: mitsuba_scene keeps the converted scene for the next call on the same Scene."""
    mitsuba_variant()
    import drjit as dr
    import mitsuba as mi

    ms = mitsuba_scene(s)
    ms.integrator.switches = Switches.for_effects(resolve_effects(s), s.render)
    params = mi.traverse(ms.mi_scene)
    keys = [f"object_{i:05d}.vertex_positions" for i in range(len(s.objects))]
    for key in keys:
        dr.enable_grad(params[key])
        dr.clear_grad(params[key])
    params.update()
    for key, o in zip(keys, s.objects):
        if normals and o.smooth and getattr(o, "normals", None) is None:
            params[key.replace("positions", "normals")] = angle_weighted_normals(mi, dr, params[key],
                                                                                  params[key.replace("vertex_positions", "faces")],
                                                                                  len(o.vertices), len(o.faces))
    params.update()
    color = backpropagated(ms, s, weights, detach)
    image = np.stack([np.array(c) for c in (color.x, color.y, color.z)], -1).reshape(s.camera.height, s.camera.width, 3)
    return image, {f"objects.{o.name}.vertices": np.array(dr.grad(params[key]), np.float64).reshape(-1, 3)
                   for key, o in zip(keys, s.objects)}


def angle_weighted_normals(mi, dr, positions, faces, vertices: int, triangles: int):
    """A mesh's vertex normals from its flat position and face buffers in Dr.Jit, differentiable: each face's
    unit normal times its corner's angle (atan2(|e1 x e2|, e1.e2)) summed per vertex by dr.scatter_reduce,
    normalised (normals.vertex_normals' definition; the meshes here have one vertex per position)."""
    fi = dr.gather(mi.Vector3u, faces, dr.arange(mi.UInt32, triangles))
    p = [dr.gather(mi.Point3f, positions, fi[c]) for c in range(3)]
    fn = dr.normalize(dr.cross(p[1] - p[0], p[2] - p[0]))
    acc = [dr.zeros(mi.Float, vertices) for _ in range(3)]
    for c in range(3):
        e1, e2 = p[(c + 1) % 3] - p[c], p[(c + 2) % 3] - p[c]
        angle = dr.atan2(dr.norm(dr.cross(e1, e2)), dr.dot(e1, e2))
        for x in range(3):
            dr.scatter_reduce(dr.ReduceOp.Add, acc[x], fn[x] * angle, fi[c])
    return dr.ravel(dr.normalize(mi.Vector3f(*acc)))


def where_images_agree(r, mitsuba, weights) -> np.ndarray:
    """``r``'s frame recorded for its gradient (render(grad=True)) against Mitsuba's image of the same model
    (``mitsuba(weights)``'s first value): ``weights`` with the pixels where the two images part (a ray on the
    other side of an edge, float32 apart) set to 0, so that both losses leave them out; 90% must agree."""
    image = r.render(grad=True).image
    m_image, _ = mitsuba(weights)
    same = (np.abs(image - m_image).max(-1) < 1e-5)[..., None]
    assert same.mean() > 0.9
    return (weights * same).astype(np.float32)


def test_gradients_through_mirrors_equal_mitsubas_ad(weights):
    """Three ray levels over the mirroring floor: the reference's own levels (its sample(), unrolled),
    Mitsuba's spawn_ray of the reflected direction, each level weighted by the k_r before it. The two
    implementations spawn the reflected rays float32 apart, and at 80 of the 1,728 pixels a reflected ray
    meets another surface or shadow (images apart by up to 5e-4); the loss leaves those pixels out (their
    weight 0) on both sides, and the gradients of the rest agree to 1e-4."""
    r = warprt.Renderer(mirror_scene())
    masked = where_images_agree(r, lambda w: mitsuba_gradients(mirror_scene(), w), weights)
    grads = r.backward(masked, wrt=list(MIRROR_PARAMETERS))
    _, m_grads = mitsuba_gradients(mirror_scene(), masked)
    names = [n for n in MIRROR_PARAMETERS if n in m_grads]
    assert "materials.floor.reflectivity" in names and len(names) >= 4
    assert [n for n in names if not np.allclose(grads[n], m_grads[n], rtol=REL, atol=REL * np.abs(m_grads[n]).max())] == []


def test_gradients_under_spot_and_directional_lights_equal_mitsubas_ad():
    """A spot (its cone's ramp in view, inverse-square) and a directional light over the mirroring floor,
    two levels: Mitsuba's own spot and directional emitters (its spot's falloff curve, its directional
    irradiance) against shading's general light model in the replay. Pixels where the two images part
    (a reflected ray or shadow ray on the other side of an edge) are left out of both losses."""
    from grad.test_light_gradients import lit

    s = lit()
    w = np.random.default_rng(5).random((s.camera.height, s.camera.width, 3)).astype(np.float32)
    r = warprt.Renderer(s)
    masked = where_images_agree(r, lambda weights: mitsuba_gradients(s, weights), w)
    names = ["materials.floor.kd", "materials.floor.ks", "materials.floor.reflectivity", "materials.ball.kd",
             "materials.ball.shininess", "lights.0.color", "lights.1.color"]
    grads = r.backward(masked, wrt=names)
    _, m_grads = mitsuba_gradients(s, masked)
    assert [n for n in names if not np.allclose(grads[n], m_grads[n], rtol=REL, atol=REL * np.abs(m_grads[n]).max())] == []
    _, unshadowed = mitsuba_gradients(s, masked, shadows=False)  # the control
    assert not np.allclose(grads["lights.1.color"], unshadowed["lights.1.color"], rtol=REL)


def mitsuba_area_gradients(s, weights, shadows: bool = True) -> tuple[np.ndarray, dict]:
    """Mitsuba's image and AD gradients of sum(weights * image) for a scene of one area light
    (reference.mitsuba_ad's: the reference's area_light() at warprt's sample points through Mitsuba's own
    emitters, and its emitted() where a ray meets the emitter), its radiance's as ``area.radiance``."""
    assert len(s.area_lights) == 1
    image, out = ad_gradients(s, weights, shadows)
    out["area.radiance"] = out.pop("area.0.radiance")
    return image, out


def test_area_light_gradients_equal_mitsubas_ad():
    """Mitsuba's Cornell box (scenes/cornell_box.xml, 24 x 24, 4 samples): the radiance of its object light,
    which the camera sees and which lights the box through soft shadows, and the three walls' kd, the 5
    pixels whose hits differ (edges) left out of both losses. Measured: within 7e-7 relative (4e-7 at 16
    samples). The control: Mitsuba's model without shadows (every sample seen) is 0.03 off in the radiance's
    gradient and 0.15 in the white walls' kd."""
    from grad.test_area_light_gradients import cornell

    s = cornell(4)
    w = np.random.default_rng(5).random((s.camera.height, s.camera.width, 3)).astype(np.float32)
    r = warprt.Renderer(s)
    masked = where_images_agree(r, lambda weights: mitsuba_area_gradients(s, weights), w)
    names = ["lights.0.radiance", "materials.white.kd", "materials.red.kd", "materials.green.kd"]
    grads = r.backward(masked, wrt=names)
    _, theirs = mitsuba_area_gradients(s, masked)
    theirs["lights.0.radiance"] = theirs.pop("area.radiance")
    assert [n for n in names if not np.allclose(grads[n], theirs[n], rtol=REL, atol=REL * np.abs(theirs[n]).max())] == []
    _, unshadowed = mitsuba_area_gradients(s, masked, shadows=False)  # the control
    assert not np.allclose(grads["lights.0.radiance"], unshadowed["area.radiance"], rtol=REL)
    assert not np.allclose(grads["materials.white.kd"], unshadowed["materials.white.kd"], rtol=REL)


def mitsuba_camera_gradients(s, weights, detach_origin: bool = False) -> tuple[np.ndarray, dict]:
    """Mitsuba's image and AD gradients of sum(weights * image) with respect to the camera: its perspective
    sensor's to_world made by Mitsuba's own look_at from an eye, center and up with dr.enable_grad, and its
    x_fov from a differentiable fovy (the sensor's fov_axis 'y' conversion, 2 atan(tan(fovy / 2) aspect));
    the camera rays from the sensor's sample_ray, their hits recomputed differentiably by Mitsuba's mesh
    intersection, the reference's levels as above. With ``detach_origin``, the rays' origin is detached from
    the eye (the control). The sensor is put back as it was."""
    mitsuba_variant()
    import drjit as dr
    import mitsuba as mi

    ms = mitsuba_scene(s)
    integ = ms.integrator
    integ.switches = Switches.for_effects(resolve_effects(s), s.render)
    cam = s.camera
    sensor = ms.sensor(cam, 1)
    p = mi.traverse(sensor)
    saved = {k: type(p[k])(p[k]) for k in ("to_world", "x_fov")}
    eye, center, up = mi.Point3f(*cam.eye), mi.Point3f(*cam.center), mi.Vector3f(*cam.up)
    fovy = mi.Float(cam.fovy)
    dr.enable_grad(eye, center, up, fovy)
    p["to_world"] = mi.Transform4f().look_at(origin=eye, target=center, up=up)
    p["x_fov"] = dr.rad2deg(2.0 * dr.atan(dr.tan(0.5 * dr.deg2rad(fovy)) * cam.width / cam.height))
    p.update()
    width, height = cam.width, cam.height
    idx = dr.arange(mi.UInt32, height * width)
    pos = mi.Point2f((mi.Float(idx % width) + 0.5) / width, (mi.Float(idx // width) + 0.5) / height)
    ray, _ = sensor.sample_ray(0.0, 0.5, pos, mi.Point2f(0.5, 0.5))
    if detach_origin:
        ray = mi.Ray3f(dr.detach(ray.o), ray.d)
    color, weight, active = mi.Color3f(0.0), mi.Color3f(1.0), mi.Bool(True)
    for depth in range(integ.max_depth()):
        ray, color, weight, active = integ.level(ms.mi_scene, ray, depth, color, weight, active)
    w = weights.reshape(-1, 3)
    dr.backward(dr.sum(color.x * mi.Float(w[:, 0]) + color.y * mi.Float(w[:, 1]) + color.z * mi.Float(w[:, 2])))
    image = np.stack([np.array(c) for c in (color.x, color.y, color.z)], -1).reshape(height, width, 3)
    out = {f"camera.{k}": np.array(dr.grad(v), np.float64).ravel() for k, v in
           (("eye", eye), ("center", center), ("up", up))}
    out["camera.fovy"] = np.float64(np.array(dr.grad(fovy)).ravel()[0])
    p["to_world"], p["x_fov"] = saved["to_world"], saved["x_fov"]
    p.update()
    return image, out


def test_camera_gradients_equal_mitsubas_ad():
    """The camera's eye, center, up and fovy (tests/grad/test_camera_gradients.py's scene: a sphere and a box
    on a mirroring floor, two ray levels, two lights, shadows) against Mitsuba's AD
    through its own perspective sensor, mesh intersection and spawn_ray, both holding each ray's face and
    visibility fixed (no boundary term either side). Pixels whose images part (a hit on the other side of an
    edge, float32 apart: 16 of 432, none without the mirror) are left out of both losses. Measured: within
    3e-4 for up, 3e-6 the rest (without the mirror, 1.1e-4 and 2e-5; not run, to save the suite 4 s). The
    control: Mitsuba's rays with their origin detached from the eye give another eye gradient."""
    from grad.test_camera_gradients import CAMERA, scene as camera_scene

    s = camera_scene(mirror=True)
    w = np.random.default_rng(5).random((s.camera.height, s.camera.width, 3)).astype(np.float32)
    r = warprt.Renderer(s)
    masked = where_images_agree(r, lambda weights: mitsuba_camera_gradients(s, weights), w)
    grads = r.backward(masked, wrt=list(CAMERA))
    _, theirs = mitsuba_camera_gradients(s, masked)
    close = lambda a, b, rel: np.allclose(a, b, rtol=rel, atol=rel * np.abs(b).max())  # noqa: E731
    assert [n for n in CAMERA if not close(grads[n], theirs[n], 1e-3)] == []
    _, detached = mitsuba_camera_gradients(s, masked, detach_origin=True)  # the control
    assert not close(detached["camera.eye"], grads["camera.eye"], 1e-2)


def test_vertex_gradients_through_mirrors_equal_mitsubas_ad():
    """tests/grad/test_vertex_gradients.py's mirroring floor (three levels) with a box and a wall seen in it:
    every object's vertices, the mirror rays leaving the moving hits. Measured: within 7.3e-5 relative of the
    largest component (each of the three objects), every pixel's images agreeing; detached, 1.1 off (floor). The control: Mitsuba's hits detached from the
    shapes (RayFlags.DetachShape) give other gradients."""
    from grad.test_vertex_gradients import HEIGHT as H, WIDTH as W, mirror_scene as vertex_mirror_scene

    s = vertex_mirror_scene()
    w = np.random.default_rng(5).random((H, W, 3)).astype(np.float32)
    r = warprt.Renderer(s)
    masked = where_images_agree(r, lambda weights: mitsuba_object_gradients(s, weights), w)
    names = [f"objects.{o.name}.vertices" for o in s.objects]
    grads = r.backward(masked, wrt=names)
    _, theirs = mitsuba_object_gradients(s, masked)
    close = lambda a, b, rel: np.allclose(a, b, rtol=rel, atol=rel * np.abs(b).max())  # noqa: E731
    assert [n for n in names if not close(grads[n], theirs[n], 1e-3)] == []
    _, detached = mitsuba_object_gradients(s, masked, detach=True)  # the control
    assert not close(grads["objects.floor.vertices"], detached["objects.floor.vertices"], 1e-2)


def test_smooth_vertex_gradients_equal_mitsubas_ad():
    """tests/grad/test_vertex_gradients.py's smooth sphere on a floor: its vertex normals move with its
    vertices (the replay's vertex_normal_sums and smooth_vertex_normals) against Mitsuba's AD with the same
    angle-weighted normals written in Dr.Jit over its positions. Measured: within 3.3e-6 relative (the sphere),
    4e-7 (the floor). The control: Mitsuba's own recomputed normals, which its AD holds fixed, are 1.1 off
    (and equal, to 8e-6, warprt's replay with the normals held)."""
    from grad.test_vertex_gradients import HEIGHT as H, WIDTH as W, smooth_scene

    s = smooth_scene()
    w = np.random.default_rng(5).random((H, W, 3)).astype(np.float32)
    r = warprt.Renderer(s)
    masked = where_images_agree(r, lambda weights: mitsuba_object_gradients(s, weights, normals=True), w)
    names = [f"objects.{o.name}.vertices" for o in s.objects]
    grads = r.backward(masked, wrt=names)
    _, theirs = mitsuba_object_gradients(s, masked, normals=True)
    close = lambda a, b, rel: np.allclose(a, b, rtol=rel, atol=rel * np.abs(b).max())  # noqa: E731
    assert [n for n in names if not close(grads[n], theirs[n], 1e-4)] == []
    _, held = mitsuba_object_gradients(s, masked)  # the control
    assert not close(grads["objects.ball.vertices"], held["objects.ball.vertices"], 1e-2)


def mitsuba_colour_gradients(s, weights, names, colours: bool = True) -> tuple[np.ndarray, dict]:
    """Mitsuba's image and AD gradients of sum(weights * image) with respect to the named objects' vertex
    colours (``names``: r.params' objects.<name>.colors) and every material's colours: the reference's
    Attributes BSDF reads each mesh's "vertex_color" attribute (mi.traverse's object_<i>.vertex_color, with
    dr.enable_grad), which its material() multiplies ka and kd by. ``colours=False``: the model without the
    vertex colours (Switches.vertex_color off; a control: the materials' gradients then miss their factor)."""
    mitsuba_variant()
    import drjit as dr
    import mitsuba as mi

    ms = mitsuba_scene(s)
    ms.integrator.switches = Switches(**{**Switches.for_effects(resolve_effects(s), s.render).__dict__,
                                         "vertex_color": colours})
    index = {o.name: i for i, o in enumerate(s.objects)}
    params = mi.traverse(ms.mi_scene)
    keys = {name: f"object_{index[name.split('.')[1]]:05d}.vertex_color" for name in names}
    for key in keys.values():
        dr.enable_grad(params[key])
        dr.clear_grad(params[key])
    params.update()
    t = ms.integrator.tables
    for table in (t.ka, t.kd, t.ks, t.shininess, t.kr):
        dr.enable_grad(table)
        dr.clear_grad(table)
    color = backpropagated(ms, s, weights)
    image = np.stack([np.array(c) for c in (color.x, color.y, color.z)], -1).reshape(s.camera.height, s.camera.width, 3)
    out = {name: np.array(dr.grad(params[key]), np.float64).reshape(-1, 3) for name, key in keys.items()}
    kd = np.array(dr.grad(t.kd), np.float64).reshape(len(np.array(t.shininess)), -1)
    ka = np.array(dr.grad(t.ka), np.float64).reshape(len(np.array(t.shininess)), -1)
    for name, m in s.materials.items():
        rows = [t.row_of_object[i] for i, o in enumerate(s.objects) if o.material == name]
        out[f"materials.{name}.kd"] = kd[rows].sum(0) + (ka[rows].sum(0) if m.ka_follows_kd else 0.0)
        out[f"materials.{name}.ka"] = ka[rows].sum(0)
    return image, out


def test_vertex_colour_gradients_equal_mitsubas_ad():
    """tests/grad/test_vertex_colour_gradients.py's scene (a coloured quad on a mirroring floor, a coloured
    triangle casting its shadow on it, two levels): the colours and the materials' ka and kd they multiply,
    against Mitsuba's AD of its Attributes BSDF's vertex_color attribute. Pixels whose images part are left out
    of both losses. Measured: within 1e-6 relative of the largest component (colours), 5e-7 (materials). The
    control: Mitsuba's model without the vertex colours gives the materials' kd other gradients."""
    from grad.test_vertex_colour_gradients import HEIGHT as H, WIDTH as W, scene as coloured_scene

    s = coloured_scene()
    w = np.random.default_rng(5).random((H, W, 3)).astype(np.float32)
    names = ["objects.quad.colors", "objects.fan.colors"]
    r = warprt.Renderer(s)
    masked = where_images_agree(r, lambda weights: mitsuba_colour_gradients(s, weights, names), w)
    materials = ["materials.paint.kd", "materials.fan.kd", "materials.fan.ka", "materials.floor.kd"]
    grads = r.backward(masked, wrt=names + materials)
    _, theirs = mitsuba_colour_gradients(s, masked, names)
    close = lambda a, b, rel: np.allclose(a, b, rtol=rel, atol=rel * np.abs(b).max())  # noqa: E731
    assert [n for n in names + materials if not close(grads[n], theirs[n], REL)] == []
    _, white = mitsuba_colour_gradients(s, masked, names, colours=False)  # the control
    assert not close(grads["materials.paint.kd"], white["materials.paint.kd"], 1e-2)
    assert not close(grads["materials.fan.kd"], white["materials.fan.kd"], 1e-2)


def mitsuba_centre_gradients(s, weights, shadows: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """Mitsuba's image and AD gradient of sum(weights * image) with respect to the centre of the scene's one
    area light, a rectangle or disk: its shape's to_world made again with a differentiable translation
    (mi.traverse, dr.enable_grad on the centre), the reference's area_light() placing warprt's sample points
    through Mitsuba's own emitter.sample_direction on it. ``shadows=False``: the model without shadows (a
    control). The shape's to_world is put back as it was."""
    mitsuba_variant()
    import drjit as dr
    import mitsuba as mi
    from warprt.scene import shape_frame

    ms = mitsuba_scene(s)
    ms.integrator.switches = Switches(**{**Switches.for_effects(resolve_effects(s), s.render).__dict__,
                                         "shadows": shadows})
    (light,) = s.area_lights
    shape = ms.integrator.tables.area_shapes[0]
    p = mi.traverse(shape)
    saved = type(p["to_world"])(p["to_world"])
    _, u, v = shape_frame(light)
    m = np.eye(4)
    m[:3, 0], m[:3, 1], m[:3, 2] = u, v, np.cross(u, v) / np.linalg.norm(np.cross(u, v))
    centre = mi.Point3f(*light.center)
    dr.enable_grad(centre)
    moved = mi.Transform4f().translate(centre) @ mi.Transform4f(m)
    p["to_world"] = moved
    p.update()
    color = backpropagated(ms, s, weights)
    image = np.stack([np.array(c) for c in (color.x, color.y, color.z)], -1).reshape(s.camera.height, s.camera.width, 3)
    grad = np.array(dr.grad(centre), np.float64).ravel()
    p["to_world"] = saved
    p.update()
    return image, grad


def test_area_light_centre_gradients_equal_mitsubas_ad():
    """tests/grad/test_area_light_shape_gradients.py's rectangle light over a glossy sphere and a mirroring
    floor (two levels, 4 samples): lights.0.center against Mitsuba's AD through its rectangle's to_world, both
    holding the faces and which sample points each hit sees. Pixels whose images part are left out of both
    losses. Measured: within 2.6e-7 relative (at 16 samples too). The control: Mitsuba's model without shadows
    (every sample point seen) is 0.21 off."""
    from grad.test_area_light_shape_gradients import HEIGHT as H, WIDTH as W, lit

    s = lit().with_render(light_samples=4)  # Mitsuba's kernels unroll the points: 16 took 74 s of the suite
    w = np.random.default_rng(5).random((H, W, 3)).astype(np.float32)
    r = warprt.Renderer(s)
    masked = where_images_agree(r, lambda weights: mitsuba_centre_gradients(s, weights), w)
    ours = r.backward(masked, wrt=["lights.0.center"])["lights.0.center"]
    _, theirs = mitsuba_centre_gradients(s, masked)
    np.testing.assert_allclose(ours, theirs, rtol=REL, atol=REL * np.abs(theirs).max())
    _, unshadowed = mitsuba_centre_gradients(s, masked, shadows=False)  # the control
    assert not np.allclose(ours, unshadowed, rtol=REL, atol=REL * np.abs(ours).max())


def test_pose_gradients_equal_mitsubas_ad_through_the_poses_jacobian():
    """tests/grad/test_pose_gradients.py's box off the origin on the mirroring floor (three levels), posed away
    from 0 (|w| = 0.46 rad): warprt's objects.<name>.translation and rotation gradients (the replay's
    posed_points on its tape) against Mitsuba's AD of the posed vertices (every object's, through its own
    spawn_ray) chained through the pose's Jacobian in NumPy (oracle.pose_gradients: Gallego and Yezzi's
    d(R u)/dw about the rest box's centre, the identity for t), for the box and for the floor (at pose 0).
    Measured: within 3.9e-5 to 6.7e-5 relative of the largest component (1e-3 asserted, as for the vertices
    through mirrors). The controls: the rotation's Jacobian about the world origin is 0.31 off, the floor's
    translation gradient read as the box's 1.1."""
    from grad.test_pose_gradients import HEIGHT as H, POSED, WIDTH as W, crate_scene
    from oracle import pose_gradients
    from warprt.image import object_poses

    w = np.random.default_rng(5).random((H, W, 3)).astype(np.float32)
    r = warprt.Renderer(crate_scene())
    r.params.update(POSED)
    s = r.scene
    masked = where_images_agree(r, lambda weights: mitsuba_object_gradients(s, weights), w)
    names = [f"objects.{o}.{k}" for o in ("crate", "floor") for k in ("translation", "rotation")]
    grads = r.backward(masked, wrt=names)
    _, vertices = mitsuba_object_gradients(s, masked)
    poses = dict(zip((o.name for o in s.objects), object_poses(s, r.poses)))
    theirs = {}
    for o in ("crate", "floor"):
        p = poses[o]
        theirs[f"objects.{o}.translation"], theirs[f"objects.{o}.rotation"] = pose_gradients(
            vertices[f"objects.{o}.vertices"], p.rest, p.centre, p.rotation)
    close = lambda a, b, rel: np.allclose(a, b, rtol=rel, atol=rel * np.abs(b).max())  # noqa: E731
    for n in names:
        print(f"{n}: {np.abs(grads[n] - theirs[n]).max() / np.abs(theirs[n]).max():.2g} of Mitsuba's largest")
    assert [n for n in names if not close(grads[n], theirs[n], 1e-3)] == []
    crate = poses["crate"]
    _, about_origin = pose_gradients(vertices["objects.crate.vertices"], crate.rest, np.zeros(3), crate.rotation)
    controls = (("about the origin", grads["objects.crate.rotation"], about_origin),
                ("the floor's translation", grads["objects.crate.translation"], theirs["objects.floor.translation"]))
    for what, a, b in controls:
        print(f"control, {what}: {np.abs(a - b).max() / np.abs(b).max():.2g} off")
        assert not close(a, b, 1e-2)
