"""Derivatives of an image (issue 30): Renderer.render(grad=True) records, per camera ray
(render.spp of them a pixel, where the trace kernel puts them) and ray level (the camera ray, then the
mirror rays the tracer follows), the hit and the lights it sees; Renderer.backward(d_image, wrt) returns
d(sum(d_image * image)) / d(param) for the parameters named as r.params names them, through a
differentiable replay of the rays' local shading over the levels (kernels/grad.py) on a wp.Tape.

What is differentiated, and what is held: each ray's face and the visibility of each light are held
fixed, as a visibility-fixed derivative is (an edge or a shadow's edge moving across pixels has no
derivative here); the local Phong terms are exact functions of the material colours and exponents, of
the lights' colours, positions and directions (point, spot and directional lights, shading's light
model: a spot's cone, 1 / r^2 falloff), of image textures' texels (the forward's bilinear wp.Texture2D
lookup written over a wp.array: kernels.bilinear), of the objects' vertices (the hit recomputed on the
moved face, through the mirror rays too, each leaving the moved hit along the direction reflected about the
moved normal; a smooth object's vertex normals made again from the moving points as the forward's Geometry
makes them, angle-weighted, kernels.vertex_normal_sums and smooth_vertex_normals, where the scene does not
give them: moving_normals), of the camera's eye, center, up and fovy (the camera rays made again in Warp,
kernels.camera_rays, and the hit recomputed on the recorded face from the moved ray, through the mirror
rays too), of the area lights' radiance (an area light's, an emitting material's emission): their
sample points' terms at each hit (the record's bit per point seen; kernels.area_replay, one thread per level
and point) and the emitter's front met by a ray, of a rectangle, disk or sphere light's centre (its sample
points translated by the centre's move, kernels.translate_samples, their normals and areas unchanged; an
object light's points, its shape and its emitting object's vertices held fixed), and of the vertex colours
(ka and kd times the colour interpolated at the hit's barycentrics, the moving ones where the hit moves;
kernels.vertex_colour: objects.<name>.colors) with every parameter above. The image is the mean of
each pixel's rays, as the trace kernel makes it. A parameter whose value switches its effect off keeps
its true derivative: a ks of 0 (the replay shades every Phong term), a light of colour 0 (its shadow rays
traced for the record), and a reflectivity of 0 where the caller names it, render(grad=[names]) recording
that material's mirror rays whatever its k_r (mirrored_materials; backward() refuses an unrecorded one in one
line rather than give it 0).

With glass (fx.refraction), Whitted's full ray tree (record_tree, replay_tree_launch; kernels/grad_tree.py):
the record follows the forward's tree level by level with the forward's own functions (each level's rays,
hits, visibility and children, the children compacted on the host into the next level's list), and the
replay is one differentiable launch per level, each level's rays in their own arrays (Warp replays neither
the forward's dynamic loop nor its in-place ray stack backwards). It differentiates a dielectric's ior,
transmittance and absorption through Fresnel, Snell and Beer, and everything above seen through the glass
(a reflectivity of 0 too, its mirror rays recorded as the chain's: mirror_anyway); held fixed besides the
faces and visibility: the tree's structure (which children exist, total internal reflection) and each ray's
medium. Its size is checked as it grows (_tree_too_big).

Covered for now: any render.spp and light_samples, camera and mirror rays, glass, image and checker
textures, vertex colours, area lights; any other scene is refused in one line naming
what is not yet differentiated, so a gradient is never silently partial.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .._warp import wp
from ..errors import ArgumentError
from ..kernels.camera import camera_data
from ..kernels.grad import (MAX_GRAD_LIGHTS, TEXTURE_CHECKER, TEXTURE_CLAMP, TEXTURE_IMAGE, TEXTURE_MIRROR, TEXTURE_NONE,
                            TEXTURE_WRAP, area_replay, camera_rays, make_area_combine,
                            make_grad_shade_kernel, sample_mean, smooth_vertex_normals, translate_samples,
                            vertex_normal_sums)
from ..kernels.grad_tree import make_tree_record_kernel, make_tree_replay_kernel, tree_area_combine, tree_camera_rays
from ..geometry import LightShape, light_shape
from ..scene import camera_basis, drawn_objects, position_ids, scene_effects
from .launch import launch_bands
from .memory import available_memory, human
from .params import object_names

SOURCE = "Renderer.backward"
MATERIAL_KEYS = ("ka", "kd", "ks", "shininess", "reflectivity")
DIELECTRIC_KEYS = ("ior", "transmittance", "absorption")  # a dielectric's, through the ray tree (record_tree)
TEXTURE_KEYS = ("ka_texture", "kd_texture", "ks_texture")  # an image texture's texels, as r.params has them
MAX_GRAD_DEPTH = 16  # ray levels, unrolled as the lights are
LIGHT_KEYS = ("color", "position", "direction")
CAMERA_KEYS = ("eye", "center", "up", "fovy")


def refusal(scene, fx, mirrored=()) -> str | None:
    """Why render(grad=True) cannot differentiate this scene yet (None: it can); ``mirrored``: the
    materials whose mirror rays are recorded whatever their reflectivity (mirrored_materials)."""
    # The replay shades every Phong term. One the scene's values leave out (every ks 0) is right to shade:
    # its derivative is not 0. One switched off (render.effects, effects=, disable=) would give another
    # image's gradient.
    called = scene_effects(scene)
    off = [name for name in ("ambient", "diffuse", "specular") if getattr(called, name) and not getattr(fx, name)]
    if off:
        return f"the gradient's replay shades every Phong term: {', '.join(off)} switched off is not differentiated yet"
    if (fx.reflection or mirrored) and not fx.refraction and scene.render.max_depth > MAX_GRAD_DEPTH:
        return f"at most {MAX_GRAD_DEPTH} ray levels (render.max_depth) are differentiated (Warp's unrolled loop)"
    if len(scene.whitted_lights) > MAX_GRAD_LIGHTS:
        return f"at most {MAX_GRAD_LIGHTS} lights are differentiated (Warp's unrolled loop)"
    return None


# Bytes per camera ray and level of the record (face, barycentrics, direction: 4 + 8 + 12, then 4 a light),
# and per camera ray of the replay (its colour and adjoint, the adjoint handed to the tape, and for camera
# gradients its direction made again and that one's adjoint: 5 x 12). With area
# lights, per camera ray and level: the emitter met (4) and a bit per sample point (in 4-byte words), and the
# replay's state (hit point, normal, kd, ks, weight, local colour, each with its adjoint: 2 x 6 x 12).
RECORD_BYTES_PER_LEVEL, RECORD_BYTES_PER_LIGHT, REPLAY_BYTES_PER_RAY = 24, 4, 60
AREA_RECORD_BYTES_PER_LEVEL, AREA_REPLAY_BYTES_PER_LEVEL = 4, 144


def area_samples(scene) -> int:
    """The area lights' sample points in all (render.light_samples each): the record's bits per ray level."""
    return len(scene.area_lights) * scene.render.light_samples


def record_bytes(scene, fx, mirrored=()) -> int:
    """What render(grad=True) and backward() hold for a frame's record and replay, in bytes: per camera
    ray (width x height x spp) and ray level."""
    cam, r = scene.camera, scene.render
    rays = cam.width * cam.height * (r.spp if fx.supersampling else 1)
    levels = ray_levels(scene, fx, mirrored)  # with glass, the least: a chain (record_tree checks the tree as
    # it grows)
    per_level = RECORD_BYTES_PER_LEVEL + RECORD_BYTES_PER_LIGHT * len(scene.whitted_lights)
    if fx.area_lights:
        per_level += AREA_RECORD_BYTES_PER_LEVEL + 4 * _words(area_samples(scene)) + AREA_REPLAY_BYTES_PER_LEVEL
    return rays * (levels * per_level + REPLAY_BYTES_PER_RAY)


def ray_levels(scene, fx, mirrored=()) -> int:
    """The ray levels a grad frame records: render.max_depth where the tracer spawns mirror rays (some
    k_r > 0) or the caller named a reflectivity to differentiate (``mirrored``), else the camera ray's."""
    return scene.render.max_depth if fx.reflection or fx.refraction or mirrored else 1


def named_parameters(scene, names) -> list[str]:
    """render(grad=[names])'s names, checked: each one backward() can differentiate in this scene (else
    one ArgumentError naming it)."""
    known = set(parameter_names(scene))
    for name in names:
        if name not in known:
            raise ArgumentError("render", "grad", f"{name!r}: " + (_name_refusal(scene, str(name)) or
                                "not a parameter backward() differentiates (Renderer.backward lists them)"))
    return list(names)


def mirrored_materials(scene, named, switched=None) -> tuple:
    """The materials whose mirror rays a grad frame records whatever their reflectivity: those whose
    ``materials.<name>.reflectivity`` the caller names (render(grad=[names])), so that a reflectivity of 0,
    which switches the mirror rays off, still gets its derivative (the colour the mirror would show); none
    where the frame cannot reflect (render.max_depth 1, or reflection switched off: ``switched``, the
    effects the caller's options leave on), its image then truly independent of the reflectivity."""
    if scene.render.max_depth <= 1 or (switched is not None and "reflection" not in switched):
        return ()
    return tuple(m for m in scene.materials if f"materials.{m}.reflectivity" in named)


def _words(samples: int) -> int:
    return max(1, -(-samples // 32))


def check_record_memory(scene, fx, device: str, mirrored=()):
    """Refuse, in one line naming the budget and the settings that reduce it, a grad=True frame whose
    record would not fit in the memory this process can still take (before the frame allocates anything)."""
    need = record_bytes(scene, fx, mirrored)
    available, what = available_memory(device)
    if available is not None and need > available:
        samples = ", render.light_samples" if fx.area_lights else ""  # a bit per area-light sample and level
        raise ArgumentError("render", "grad", f"the gradient's record of this frame needs about {human(need)} "
                            f"(per camera ray and ray level), more than the {human(available)} {what}: lower "
                            f"render.spp, render.max_depth{samples} or camera.width and camera.height")


@dataclass
class FirstHits:
    """What a grad=True frame recorded: per camera ray (``samples`` per pixel, ray pixel * samples +
    sample, the tracer's strata) and ray level (``levels``: the camera ray, then the mirror rays) the
    hit's face (-1: none, -2: no ray at that level), barycentrics and ray direction, and per light
    whether the hit saw it; with area lights (``words`` > 0), the area light whose emitting side the ray met
    (``emit``, -1: none) and a bit per area-light sample point the hit sees (``area_bits``, ``words`` int32s
    a level)."""

    face: wp.array
    bary: wp.array
    dirs: wp.array
    visible: wp.array
    width: int
    height: int
    lights: int
    levels: int
    smooth: bool
    samples: int = 1
    light_model: bool = False  # shading's general light model (spot, directional, falloff), as the frame's
    texture: bool = False  # textured colours, as the frame's
    emit: wp.array | None = None
    area_bits: wp.array | None = None
    words: int = 0  # 0: no area lights
    area: object = None  # the frame's AreaLights table (its sample points, normals and areas), as recorded
    mirrored: tuple = ()  # the materials whose mirror rays were recorded whatever their k_r (mirrored_materials)
    reflects: bool = False  # whether the frame could reflect (render.max_depth > 1, reflection not switched off)
    vertex_color: bool = False  # ka and kd times the vertex colours, as the frame's


def parameter_names(scene) -> list[str]:
    """The r.params names backward() can differentiate with respect to: the objects' vertices too (a smooth
    object's computed vertex normals moving with them), but not an area light's own object's (its sample
    points are held fixed), and their vertex colours where they have them; an area light's radiance and an
    emitting material's emission, a rectangle, disk or sphere light's center; the camera's eye, center, up
    and fovy."""
    names = [f"materials.{m}.{k}" for m in scene.materials for k in MATERIAL_KEYS]
    names += [f"materials.{name}.{k}" for name, m in scene.materials.items() if m.dielectric for k in DIELECTRIC_KEYS]
    names += [f"materials.{name}.{k}" for name, m in scene.materials.items() for k in TEXTURE_KEYS
              if getattr(m, k) is not None and getattr(m, k).image is not None]
    names += [f"materials.{name}.emission" for name, m in scene.materials.items() if _emits(m)]
    names += [f"lights.{i}.{k}" for i, light in enumerate(scene.lights) if not light.area for k in LIGHT_KEYS
              if getattr(light, k) is not None]  # as r.params has them: no position for a directional light
    names += [f"lights.{i}.radiance" for i, light in enumerate(scene.lights) if light.area]
    names += [f"lights.{i}.center" for i, light in enumerate(scene.lights) if _centred(light)]
    emitters = _emitter_objects(scene)
    names += [f"objects.{name}.vertices" for name, i in object_names(scene).items()
              if scene.objects[i].name not in emitters]
    names += [f"objects.{name}.colors" for name, i in object_names(scene).items()
              if scene.objects[i].colors is not None]
    names += [f"camera.{k}" for k in CAMERA_KEYS]
    return names


def _centred(light) -> bool:
    """Whether a light is an area light of its own shape (rectangle, disk, sphere) with a ``center``, which
    r.params names and whose move translates its sample points (translate_samples)."""
    return light.area and light.shape is not None and light.center is not None


def _emits(material) -> bool:
    """Whether a material's emission makes its objects area lights (Scene.emissive_lights' rule)."""
    return material.emission is not None and max(material.emission) > 0.0


def _emitter_objects(scene) -> set:
    """The names of the objects that are area lights (a light's ``object``, an emitting material's)."""
    return {light.object for light in scene.area_lights if light.object is not None}


def area_sources(scene) -> list[str]:
    """Per area light (scene.area_lights' order, the kernels' table's), the r.params name its radiance is:
    an area light's lights.<i>.radiance, an emitting material's materials.<name>.emission (one light per
    object name of that material, Scene.emissive_lights)."""
    out = [f"lights.{i}.radiance" for i, light in enumerate(scene.lights) if light.area]
    named = set()
    for o in scene.objects:  # Scene.emissive_lights' loop, to name each light's material
        m = scene.materials.get(o.material)
        if m is not None and _emits(m) and o.name not in named:
            named.add(o.name)
            out.append(f"materials.{o.material}.emission")
    assert len(out) == len(scene.area_lights)
    return out


def _name_refusal(scene, name: str) -> str | None:
    """Why backward() cannot differentiate r.params' ``name`` in this scene (None: it can or it is unknown)."""
    section, owner, key = (name.split(".") + ["", "", ""])[:3]
    if section == "objects" and owner in object_names(scene) and \
            scene.objects[object_names(scene)[owner]].name in _emitter_objects(scene):
        return ("the object is an area light: its sample points (the light's position and shape) are held fixed, "
                "not differentiated yet")
    if section == "materials" and key == "emission" and owner in scene.materials and \
            scene.materials[owner].emission is not None and not _emits(scene.materials[owner]):
        return ("an emission of 0 makes no area light (no sample points to differentiate): give it a positive "
                "value")
    return None


def _unrecorded(scene, geom, hits: FirstHits, name: str) -> bool:
    """Whether ``name`` is a reflectivity of 0 (every component) of a material the frame's objects use, whose
    mirror rays the frame did not record though it could reflect: its derivative, the mirrored colour, is
    not in the record (render(grad=[name]) records it)."""
    section, owner, key = (name.split(".") + ["", "", ""])[:3]
    if section != "materials" or key != "reflectivity" or owner not in geom.material_names:
        return False
    m = scene.materials[owner]
    if isinstance(hits, TreeHits) and m.dielectric:  # a k_r > 0 makes glass a mirror: a jump, not a slope
        return False
    return hits.reflects and owner not in hits.mirrored and max(m.reflectivity) <= 0.0


def _frame_refusal(scene, geom, hits, name: str) -> str | None:
    """Why backward() cannot differentiate ``name`` at this recorded frame (None: it can): a reflectivity
    of 0 the record holds no mirror rays for."""
    if _unrecorded(scene, geom, hits, name):
        return (f"a reflectivity of 0 switches the mirror rays off, and this frame did not record them: render "
                f"with grad=[{name!r}] (its mirror rays recorded for its derivative)")
    return None


@dataclass
class ReplayLaunch:
    """The differentiable replay of a recorded frame, ready to launch: kernels/grad.py's shade kernel
    over ``dim`` camera rays with ``inputs``, writing each ray's colour to ``rays``; ``arrays`` the
    inputs it differentiates, by key: ka, kd, ks, shininess, reflectivity per material slot, color,
    position and direction per Whitted light, radiance per area light, with vertices the geometry's
    points, with vertex colours their per-vertex colors, with centres each area light's center (its shift). With area lights, the shade kernel writes each level's state (its ``rays`` a stand-in) and
    ``then`` holds the launches after it, (kernel, dim, inputs, outputs): the area lights' samples
    (kernels.area_replay) and the levels' sum into ``rays`` (make_area_combine)."""

    kernel: object
    dim: int
    inputs: list
    rays: wp.array
    arrays: dict
    images: dict  # TextureTable.images: where each textured colour's texels lie in arrays["texels"]
    then: list = None
    shaded: wp.array = None  # the shade kernel's output: ``rays`` without area lights
    before: list = None  # launches before the shade kernel's (with the camera: camera_rays)


def replay(scene, geom, hits: FirstHits, device: str, vertices: bool = False, camera: bool = False,
           centres: bool = False) -> ReplayLaunch:
    """replay_launch's kernels launched, on the current wp.Tape if there is one: its ``rays`` hold each
    camera ray's colour (one per pixel and sample)."""
    if isinstance(hits, TreeHits):
        r = replay_tree_launch(scene, geom, hits, device, vertices, camera, centres)
    else:
        r = replay_launch(scene, geom, hits, device, vertices, camera, centres)
    for kernel, dim, inputs, outputs in r.before or ():
        wp.launch(kernel, dim=dim, inputs=inputs, outputs=outputs, device=device)
    if r.kernel is not None:  # a tree's levels are all in ``then``
        wp.launch(r.kernel, dim=r.dim, inputs=r.inputs, outputs=[r.shaded], device=device)
    for kernel, dim, inputs, outputs in r.then or ():
        wp.launch(kernel, dim=dim, inputs=inputs, outputs=outputs, device=device)
    return r


def replay_arrays(scene, geom, mats, device: str) -> tuple:
    """The replays' material and Whitted-light inputs (the chain's and the tree's), from the scene's values:
    per material slot (``mats``, geom.slot_materials) ka, kd, ks, shininess and reflectivity, per light its
    position, colour, falloff, kind, axis (unit, as Light keeps it: backward() projects its adjoint) and
    cone; the colours, exponents, positions and axes differentiable."""
    vec = lambda rows: wp.array(np.asarray(rows, np.float32).reshape(-1, 3), dtype=wp.vec3, device=device,  # noqa: E731
                                requires_grad=True)
    ka, kd, ks, kr = (vec([getattr(m, k) for m in mats] or [[0, 0, 0]]) for k in ("ka", "kd", "ks", "reflectivity"))
    shininess = wp.array(np.asarray([m.shininess for m in mats] or [0.0], np.float32), dtype=float, device=device,
                         requires_grad=True)
    lights = scene.whitted_lights
    light_pos = vec(geom.light_positions(scene) if lights else [[0, 0, 0]])
    light_color = vec([l.color for l in lights] or [[0, 0, 0]])
    shapes = [light_shape(l) for l in lights] or [LightShape()]
    ints = lambda values: wp.array(np.asarray(values, np.int32), dtype=int, device=device)  # noqa: E731
    inverse_square, kind = ints([x.inverse_square for x in shapes]), ints([x.kind for x in shapes])
    axis = vec([list(x.direction) for x in shapes])
    cone = wp.array(np.asarray([[x.cos_cutoff, x.cos_beam, x.cutoff, x.inv_ramp] for x in shapes], np.float32),
                    dtype=wp.vec4, device=device)
    return ka, kd, ks, shininess, kr, light_pos, light_color, inverse_square, kind, axis, cone


def replay_launch(scene, geom, hits: FirstHits, device: str, vertices: bool = False,
                  camera: bool = False, centres: bool = False) -> ReplayLaunch:
    """The replay of ``hits`` (a frame of ``scene`` on ``geom``) with its differentiable arrays made from
    the scene's values; with ``vertices``, the points too (the hits recomputed on the moved faces); with
    ``camera``, the camera too: its eye, center and up (``arrays["camera"]``, the eye and
    center relative to the frame origin) and fovy, the camera rays' directions made from them (camera_rays,
    in ``before``) and the hits recomputed from the moved rays on the recorded faces; with ``centres`` (and area
    lights), the area lights' sample points translated by their centres' moves (``arrays["center"]``, 0:
    translate_samples, in ``before``), which the area lights' replay then reads."""
    mats = geom.slot_materials(scene)
    vec = lambda rows: wp.array(np.asarray(rows, np.float32).reshape(-1, 3), dtype=wp.vec3, device=device,  # noqa: E731
                                requires_grad=True)
    ka, kd, ks, shininess, kr, light_pos, light_color, inverse_square, kind, axis, cone = replay_arrays(
        scene, geom, mats, device)
    n = hits.width * hits.height * hits.samples
    rays = wp.zeros(n, dtype=wp.vec3, device=device, requires_grad=True)
    points = wp.array(geom.points_np, dtype=wp.vec3, device=device, requires_grad=True) if vertices else geom.points
    area = hits.words > 0
    kernel = make_grad_shade_kernel(hits.lights, hits.levels, hits.smooth, vertices or camera, hits.light_model,
                                    hits.texture, area, hits.vertex_color)
    cam = scene.camera
    eye = vec([geom.eye_offset(cam.eye), geom.eye_offset(cam.center), cam.up])  # eye[0]: the rays' origin
    fovy = wp.array([cam.fovy], dtype=float, device=device, requires_grad=True)
    dirs, before = hits.dirs, []
    if camera:  # the camera rays made again, differentiable in the camera, the recorded directions unused
        dirs = wp.zeros(n * hits.levels, dtype=wp.vec3, device=device, requires_grad=True)
        before.append((camera_rays, n, [eye, fovy, float(cam.near), hits.width, hits.height,
                                        math.isqrt(hits.samples), hits.levels], [dirs]))
    # each level's direction, as the moving replay makes it (vertices, camera): what the area lights' replay reads
    ray_dirs = wp.zeros(n * hits.levels if vertices or camera else 1, dtype=wp.vec3, device=device,
                        requires_grad=True)
    table = texture_table(mats, device)
    uvs = geom.uv_array() if hits.texture else wp.zeros(1, dtype=wp.vec2, device=device)
    background = wp.vec3(*scene.render.background)
    levels = n * hits.levels if area else 1  # the area lights' per-level state (stand-ins without)
    state = [wp.zeros(levels, dtype=wp.vec3, device=device, requires_grad=True) for _ in range(6)]
    shaded = wp.zeros(1, dtype=wp.vec3, device=device, requires_grad=True) if area else rays
    normals = geom.normals
    if vertices and hits.smooth:  # a smooth object's vertex normals, computed from the moving points
        normals, launches = moving_normals(scene, geom, points, device)
        before += launches
    colors = vertex_colours(geom, hits, device)  # ka's and kd's factor, per vertex
    inputs = [eye, points, geom.indices, normals, geom.tri_material, geom.tri_smooth, ka, kd, ks, shininess, kr,
              light_pos, light_color, inverse_square, kind, axis, cone, uvs, *table.arrays,
              wp.vec3(*scene.render.ambient), background, hits.face, hits.bary, dirs, hits.visible, *state, ray_dirs,
              colors]
    arrays = {"ka": ka, "kd": kd, "ks": ks, "shininess": shininess, "reflectivity": kr, "color": light_color,
              "position": light_pos, "direction": axis, "texels": table.arrays[0]}
    if hits.vertex_color:
        arrays["colors"] = colors
    then = []
    if area:
        a = hits.area  # the forward's own sample points, normals and areas
        first = a.first.numpy()
        sample_light = wp.array(np.repeat(np.arange(len(first) - 1), np.diff(first)).astype(np.int32), dtype=int,
                                device=device)
        radiance = vec([l.radiance for l in scene.area_lights])
        arrays["radiance"] = radiance
        samples = a.points
        if centres:  # the sample points moved with their light's centre (c - c0, 0 here: the forward's points
            # to the bit), their normals and areas as they are: a shape light's points are its centre plus
            # fixed offsets
            shift = wp.zeros(len(scene.area_lights), dtype=wp.vec3, device=device, requires_grad=True)
            samples = wp.zeros(int(first[-1]), dtype=wp.vec3, device=device, requires_grad=True)
            before.append((translate_samples, int(first[-1]), [a.points, sample_light, shift], [samples]))
            arrays["center"] = shift
        hit_p, hit_n, hit_kd, hit_ks, level_weight, acc = state
        then.append((area_replay, (levels, int(first[-1])),
                     [hits.words, hits.face, ray_dirs if vertices or camera else dirs, hits.area_bits, geom.tri_material, shininess, hit_p, hit_n,
                      hit_kd, hit_ks, samples, a.normals, a.dA, sample_light, radiance], [acc]))
        then.append((make_area_combine(hits.levels), n, [hits.face, hits.emit, radiance, background, level_weight,
                                                         acc], [rays]))
    if vertices:
        arrays["points"] = points
    if camera:
        arrays["camera"], arrays["fovy"] = eye, fovy
    return ReplayLaunch(kernel, n, inputs, rays, arrays, table.images, then, shaded, before)


def vertex_colours(geom, hits: FirstHits, device: str) -> wp.array:
    """The shade kernel's per-vertex colours: the forward's (Geometry.colors, white where an object has
    none), differentiable, where the frame has vertex colours; else the forward's one-entry stand-in."""
    if not hits.vertex_color:
        return geom.colors
    return wp.array(geom.colors.numpy(), dtype=wp.vec3, device=device, requires_grad=True)


def moving_normals(scene, geom, points, device: str) -> tuple:
    """(normals, launches): the vertex normals the forward's Geometry makes from the objects' vertices
    (Geometry._placed: normals.vertex_normals, angle-weighted and shared by the vertices at one position,
    where a smooth object has no normals of its own; the given ones, a file's or a crease's, kept as they
    are when the vertices move), differentiable in ``points`` through the launches (vertex_normal_sums, then
    smooth_vertex_normals) that make them. Which vertices share a position is held as it is: a direction
    that parts two vertices at one position (a seam's) moves the forward's normals by a jump, not a slope."""
    objects = drawn_objects(scene)
    position, faces, base, face_base, unique = [], [], 0, 0, 0
    for obj in objects:
        count = len(obj.vertices)
        if obj.smooth and getattr(obj, "normals", None) is None:
            ids = position_ids(obj.vertices)
            position.append(ids + unique)
            unique += int(ids.max()) + 1 if count else 0
            faces.append(np.arange(face_base, face_base + len(obj.faces)))
        else:
            position.append(np.full(count, -1))
        base += count
        face_base += len(obj.faces)
    if not faces:
        return geom.normals, []
    position = wp.array(np.concatenate(position).astype(np.int32), dtype=int, device=device)
    faces = wp.array(np.concatenate(faces).astype(np.int32), dtype=int, device=device)
    sums = wp.zeros(unique, dtype=wp.vec3, device=device, requires_grad=True)
    normals = wp.zeros(base, dtype=wp.vec3, device=device, requires_grad=True)
    return normals, [(vertex_normal_sums, len(faces), [points, geom.indices, faces, position], [sums]),
                     (smooth_vertex_normals, base, [sums, position, geom.normals], [normals])]


@dataclass
class TextureTable:
    """The colours' textures as the replay reads them: ``arrays`` the shade kernel's texels (every image
    texture's, one copy per material slot and colour, so that each has its own adjoint; differentiable),
    per row 3 m + (0, 1, 2) for slot m's ka, kd, ks: (kind, offset, width, height), the wrap per axis, the
    uv map's two rows, the checker's two colours; ``images`` {(slot, key): (offset, height, width)}."""

    arrays: list
    images: dict


WRAPS = {"repeat": TEXTURE_WRAP, "clamp": TEXTURE_CLAMP, "mirror": TEXTURE_MIRROR}


def texture_table(mats, device: str) -> TextureTable:
    """The TextureTable of the material slots ``mats`` (geom.slot_materials)."""
    texels, shape, wrap, u_map, v_map, c0, c1, images = [np.ones((1, 3), np.float32)], [], [], [], [], [], [], {}
    offset = 1  # texel 0: a stand-in, so that the array is never empty
    for slot, m in enumerate(mats):
        for key in ("ka", "kd", "ks"):
            t = getattr(m, f"{key}_texture")
            row = (TEXTURE_NONE, 0, 1, 1)
            a = (1.0, 0.0, 0.0, 0.0, 1.0, 0.0) if t is None else t.uv_transform
            colours = ((1.0, 1.0, 1.0),) * 2
            modes = (TEXTURE_WRAP, TEXTURE_WRAP)
            if t is not None and t.checker is not None:
                row, colours = (TEXTURE_CHECKER, 0, 1, 1), t.checker
            elif t is not None:
                h, w = t.image.shape[:2]
                row, modes = (TEXTURE_IMAGE, offset, w, h), (WRAPS[t.wrap[0]], WRAPS[t.wrap[1]])
                texels.append(np.asarray(t.image, np.float32)[..., :3].reshape(-1, 3))
                images[(slot, key)] = (offset, h, w)
                offset += h * w
            shape.append(row)
            wrap.append(modes)
            u_map.append(a[:3])
            v_map.append(a[3:])
            c0.append(colours[0])
            c1.append(colours[1])
    vec = lambda rows, grad=False: wp.array(np.asarray(rows if len(rows) else [[1.0, 1.0, 1.0]], np.float32)  # noqa: E731
                                            .reshape(-1, 3), dtype=wp.vec3, device=device, requires_grad=grad)
    arrays = [vec(np.concatenate(texels), True),
              wp.array(np.asarray(shape or [(TEXTURE_NONE, 0, 1, 1)], np.int32), dtype=wp.vec4i, device=device),
              wp.array(np.asarray(wrap or [(0, 0)], np.int32), dtype=wp.vec2i, device=device),
              vec(u_map), vec(v_map), vec(c0), vec(c1)]
    return TextureTable(arrays, images)


def replay_image(scene, geom, hits: FirstHits, device: str, camera: bool = False, centres: bool = False) -> np.ndarray:
    """The image the replay makes of a recorded frame, (height, width, 3): the forward's, to float32
    rounding, where the replay models what the forward traced (what the tests check); with ``camera``, the
    replay camera gradients run (the rays made again from the camera, the hits re-intersected); with ``centres``,
    the area lights' sample points translated (by 0) as the replay of their centres' gradients does."""
    rays = replay(scene, geom, hits, device, camera=camera, centres=centres).rays
    image = wp.empty(hits.width * hits.height, dtype=wp.vec3, device=device)
    wp.launch(sample_mean, dim=hits.width * hits.height, inputs=[rays, hits.samples], outputs=[image], device=device)
    return image.numpy().reshape(hits.height, hits.width, 3)


def backward(scene, geom, hits: FirstHits, d_image, wrt, device: str) -> dict:
    """{name: d(sum(d_image * image)) / d(param)} for each name in ``wrt`` (parameter_names), each shaped
    as the parameter: (3,) for colours and positions, () for an exponent."""
    known = parameter_names(scene)
    if wrt is None:  # everything this frame can be differentiated in
        wrt = [n for n in known if _frame_refusal(scene, geom, hits, n) is None]
    wrt = list(wrt)
    for name in wrt:
        if name not in known:
            why = _name_refusal(scene, str(name)) or (
                "not a parameter backward() differentiates yet (materials.<name>.ka | kd | ks | shininess | "
                "reflectivity | ka_texture | kd_texture | ks_texture | emission, a dielectric's ior | "
                "transmittance | absorption, lights.<i>.color | position | direction | radiance | center (an "
                "area light's of its own shape), objects.<name>.vertices | colors (vertex colours), "
                "camera.eye | center | up | fovy)")
            raise ArgumentError("backward", str(name), why)
        why = _frame_refusal(scene, geom, hits, name)
        if why is not None:
            raise ArgumentError("backward", str(name), why)
    d = np.asarray(d_image.numpy() if isinstance(d_image, wp.array) else d_image, np.float32)
    if d.shape != (hits.height, hits.width, 3) or not np.all(np.isfinite(d)):
        raise ArgumentError("backward", "d_image", f"expected finite values of shape {(hits.height, hits.width, 3)}, "
                                                   f"got {d.shape}")
    moving = any(name.startswith("objects.") and name.endswith(".vertices") for name in wrt)
    camera = any(name.startswith("camera.") for name in wrt)
    centres = any(name.startswith("lights.") and name.endswith(".center") for name in wrt)
    tape = wp.Tape()
    with tape:
        launched = replay(scene, geom, hits, device, moving, camera, centres)
    rays, arrays = launched.rays, launched.arrays
    # The image is the mean of each pixel's rays (sample_mean): its adjoint, d_image / samples to each ray.
    d_rays = np.repeat(d.reshape(-1, 3), hits.samples, axis=0) / np.float32(hits.samples)
    tape.backward(grads={rays: wp.array(d_rays, dtype=wp.vec3, device=device)})
    slot = {name: i for i, name in enumerate(geom.material_names)}
    whitted = [i for i, light in enumerate(scene.lights) if not light.area]
    grads = {k: a.grad.numpy() for k, a in arrays.items() if k != "points"}
    camera_rows = {key: i for i, key in enumerate(CAMERA_KEYS[:3])}

    def texels(slot: int, key: str) -> np.ndarray:  # a texture's adjoint, (H, W, 3) with row 0 at the top
        offset, h, w = launched.images[(slot, key)]
        return grads["texels"][offset:offset + h * w].reshape(h, w, 3)[::-1].astype(np.float64)

    starts = np.cumsum([0] + [len(o.vertices) for o in scene.objects])
    if moving:
        point_grads = arrays["points"].grad.numpy().astype(np.float64)
    out = {}
    for name in wrt:
        section, owner, key = (name.split(".") + [""])[:3]  # camera.<key>: two parts
        if section == "objects":  # the points are the objects' vertices in order, less the frame origin
            i = object_names(scene)[owner]
            if key == "colors":  # the colours likewise, one per vertex
                out[name] = grads["colors"][starts[i]:starts[i + 1]].astype(np.float64)
                continue
            out[name] = point_grads[starts[i]:starts[i + 1]]
        elif section == "camera":  # eye and center less the frame origin (a shift: the same derivative), up
            out[name] = (grads["fovy"][0] if owner == "fovy" else grads["camera"][camera_rows[owner]]).astype(np.float64)
        elif key == "center":  # an area light's: its row among the area lights (area_sources' order)
            out[name] = grads["center"][area_sources(scene).index(f"lights.{owner}.radiance")].astype(np.float64)
        elif key in ("radiance", "emission"):  # the area lights whose radiance it is
            rows = [j for j, source in enumerate(area_sources(scene)) if source == name]
            out[name] = grads["radiance"][rows].astype(np.float64).sum(0) if rows else np.zeros(3)
        elif section == "materials":
            if owner not in slot:  # a material no object uses
                texture = getattr(scene.materials[owner], key, None) if key in TEXTURE_KEYS else None
                out[name] = np.zeros(() if key in ("shininess", "ior") else texture.image.shape if texture else (3,))
                continue
            if key in DIELECTRIC_KEYS and key not in grads:  # a frame without the tree (max_depth 1): no glass
                out[name] = np.zeros(() if key == "ior" else (3,))
                continue
            if key in TEXTURE_KEYS:
                out[name] = texels(slot[owner], key[:2])
                if key == "kd_texture" and scene.materials[owner].ka_texture_follows_kd:  # as ka follows kd
                    out[name] = out[name] + texels(slot[owner], "ka")
                continue
            out[name] = grads[key][slot[owner]].astype(np.float64)
            if key == "kd" and scene.materials[owner].ka_follows_kd:  # ka is kd there (r.params keeps it so)
                out[name] = out[name] + grads["ka"][slot[owner]]
        else:
            out[name] = grads[key][whitted.index(int(owner))].astype(np.float64)
            if key == "direction":  # Light keeps d / |d| of the d it is given, |d| = 1: (I - d d^T) adjoint
                unit = np.asarray(scene.lights[int(owner)].direction, np.float64)
                out[name] = out[name] - unit * (unit @ out[name])
    tape.zero()
    return out


# --- Glass: Whitted's full ray tree (kernels/grad_tree.py) --------------------------------------------------

# Bytes per ray of the recorded tree (any level): the record's face, medium, camera ray, child kind and the
# children's places (4 + 4 + 4 + 4 + 8), 4 a light; the replay's origin, direction, weight and segment start,
# each with its adjoint (2 x 4 x 12); and while recording, the level's rays and children and their reaches
# (12 x 12 + 12 + 8).
# With area lights, per ray: the emitter met (4) and a bit per sample point (in 4-byte words), and the
# replay's state (hit point, normal, kd, ks, weight, local colour, direction, each with its adjoint: 2 x 7 x 12).
TREE_BYTES_PER_RAY, TREE_RECORD_BYTES_PER_RAY, TREE_AREA_BYTES_PER_RAY = 24 + 96, 164, 4 + 168


@dataclass
class TreeLevel:
    """One level of a recorded ray tree: per ray of its list (``count``), the hit's face (-1: none), which
    lights it sees (``lights`` ints a ray), its medium (-1: air), its camera ray, what it spawns
    (grad_tree.CHILD_*) and its children's places in the next level's list (reflected, transmitted; -1:
    none); the first level's directions too (the camera rays', as the forward traced them); with area
    lights, the emitter each ray met (-1: none) and a bit per sample point its hit sees (TreeHits.words
    int32s a ray)."""

    face: wp.array
    visible: wp.array
    medium: wp.array
    ray_of: wp.array
    kind: wp.array
    child: wp.array
    count: int
    dirs: wp.array | None = None
    emit: wp.array | None = None
    area_bits: wp.array | None = None


@dataclass
class TreeHits:
    """What a grad=True frame with glass recorded: the forward's ray tree per camera ray, level by level
    (``tree``, TreeLevels: the camera rays, then each level's children in their parents' order), the
    counterpart of FirstHits for replay() and backward(). ``absorption``: whether the replay applies
    Beer's law (unless switched off, also where every absorption is 0: its derivative is not)."""

    tree: list
    width: int
    height: int
    lights: int
    levels: int  # render.max_depth
    smooth: bool
    samples: int = 1
    light_model: bool = False
    texture: bool = False
    absorption: bool = True
    words: int = 0  # 0: no area lights
    area: object = None  # the frame's AreaLights table, as recorded
    mirrored: tuple = ()  # the opaque materials whose mirror rays were recorded whatever their k_r
    vertex_color: bool = False  # ka and kd times the vertex colours, as the frame's
    reflects: bool = True  # its levels could hold mirror rays

    @property
    def rays(self) -> int:
        """The rays the tree holds, all levels."""
        return sum(level.count for level in self.tree)


def _tree_too_big(scene, need: int, device: str):
    """The one error for a tree whose record would not fit, naming the settings that make it smaller."""
    available, what = available_memory(device)
    if available is not None and need > available:
        samples = ", render.light_samples" if scene.area_lights else ""
        raise ArgumentError("render", "grad", f"the gradient's record of this frame's ray tree (glass) needs about "
                            f"{human(need)} or more, more than the {human(available)} {what}: lower render.max_depth "
                            f"(each level may double the rays), render.spp{samples} or camera.width and camera.height")


def record_tree(scene, geom, data, fx, device: str, threads: int = 1, bands: int = 1, pool=None,
                switched=None, mirrored=()) -> TreeHits:
    """record_first_hits for a scene with glass: the forward's ray tree, one launch of grad_tree's record
    kernel a level (in ``bands`` bands on ``threads`` threads), the children of each level compacted on the
    host into the next level's list (the reflected before the transmitted, parents in order); the rays'
    origins, directions, weights and media are the forward's to the bit (the same functions make them). Where
    a dielectric's transmittance is 0 the tree also holds the refracted rays the forward leaves out (weight
    0: the image is the same), whose radiance is that transmittance's derivative.
    The memory the tree takes is checked as it grows (_tree_too_big)."""
    cam, L, D = scene.camera, len(scene.whitted_lights), scene.render.max_depth
    k = math.isqrt(scene.render.spp) if fx.supersampling else 1
    n = cam.width * cam.height * k * k
    wanted = switched is None or "shadows" in switched
    shadows = fx.shadows or (scene.render.shadows and wanted and not scene_effects(scene).shadows)
    absorb = fx.absorption or ((switched is None or "absorption" in switched) and not scene_effects(scene).absorption)
    c = camera_data(camera_basis(cam), geom.eye_offset(cam.eye))
    v3 = lambda m: wp.zeros(max(m, 1), dtype=wp.vec3, device=device)  # noqa: E731
    i1 = lambda m: wp.zeros(max(m, 1), dtype=int, device=device)  # noqa: E731
    orig, dirs, weight, start, medium = v3(n), v3(n), v3(n), v3(n), i1(n)
    launch_bands(tree_camera_rays, lambda first: [data, c, k, first, orig, dirs, weight, start, medium], n, threads,
                 bands, device, pool=pool)
    reach = wp.array(np.ones((max(n, 1), 3), np.float32), dtype=wp.vec3, device=device)  # the camera rays': 1
    words = _words(area_samples(scene)) if fx.area_lights else 0
    # The opaque materials named by render(grad=[...reflectivity]): their mirror rays recorded whatever their k_r
    # (a dielectric's k_r > 0 makes it a mirror: a jump, not a slope).
    mirrored = tuple(m for m in mirrored if not scene.materials[m].dielectric)
    anyway = wp.array(np.asarray([int(m in mirrored) for m in geom.material_names] or [0], np.int32), dtype=int,
                      device=device)
    kernel = make_tree_record_kernel(L, fx.smooth, shadows, fx.culling, fx.light_model, fx.reflection or bool(mirrored),
                                     fx.absorption, bool(words))
    per_ray = TREE_BYTES_PER_RAY + 4 * L + (TREE_AREA_BYTES_PER_RAY + 4 * words if words else 0)
    ray_of, levels, held = np.arange(n, dtype=np.int32), [], 0
    for level in range(D):
        m = len(ray_of)
        held += m
        _tree_too_big(scene, held * per_ray + m * TREE_RECORD_BYTES_PER_RAY, device)
        face, kind, visible = i1(m), i1(m), wp.zeros(max(m * L, 1), dtype=int, device=device)
        has = wp.zeros(max(m, 1), dtype=wp.vec2i, device=device)
        hit_p, o_r, d_r, w_r, o_t, d_t, w_t, x_r, x_t = (v3(m) for _ in range(9))
        med_r, med_t = i1(m), i1(m)
        emit = wp.full(max(m, 1) if words else 1, -1, dtype=int, device=device)
        area_bits = wp.zeros(max(m * words, 1), dtype=int, device=device)
        launch_bands(kernel, lambda first: [data, D, level, first, orig, dirs, weight, start, medium, face,
                                            visible, kind, has, hit_p, o_r, d_r, w_r, med_r, o_t, d_t, w_t, med_t,
                                            emit, area_bits, words, reach, x_r, x_t, anyway],
                     m, threads, bands, device, pool=pool)
        h = has.numpy()[:m]
        hr, ht = h[:, 0] != 0, h[:, 1] != 0
        per = hr.astype(np.int32) + ht
        base = np.cumsum(per, dtype=np.int64) - per
        child = np.stack([np.where(hr, base, -1), np.where(ht, base + hr, -1)], 1).astype(np.int32)
        levels.append(TreeLevel(face, visible, medium, wp.array(ray_of if m else np.zeros(1, np.int32), dtype=int,
                                                               device=device),
                                kind, wp.array(child if m else np.zeros((1, 2), np.int32), dtype=wp.vec2i,
                                               device=device), m, dirs if level == 0 else None, emit, area_bits))
        total = int(per.sum())
        if total == 0 or level + 1 == D:
            break

        def gather(a_r, a_t, dtype):  # the next level's list: each child at its place
            r, t = a_r.numpy()[:m], a_t.numpy()[:m]
            out = np.empty((total,) + r.shape[1:], r.dtype)
            out[child[hr, 0]] = r[hr]
            out[child[ht, 1]] = t[ht]
            return wp.array(out, dtype=dtype, device=device)

        orig, dirs, weight = gather(o_r, o_t, wp.vec3), gather(d_r, d_t, wp.vec3), gather(w_r, w_t, wp.vec3)
        reach = gather(x_r, x_t, wp.vec3)
        start, medium = gather(hit_p, hit_p, wp.vec3), gather(med_r, med_t, int)
        nxt = np.empty(total, np.int32)
        nxt[child[hr, 0]] = ray_of[hr]
        nxt[child[ht, 1]] = ray_of[ht]
        ray_of = nxt
    return TreeHits(levels, cam.width, cam.height, L, D, fx.smooth, k * k, fx.light_model, fx.texture, absorb, words,
                    data.area if words else None, mirrored=mirrored, vertex_color=fx.vertex_color)


def replay_tree_launch(scene, geom, hits: TreeHits, device: str, vertices: bool = False,
                       camera: bool = False, centres: bool = False) -> ReplayLaunch:
    """replay_launch for a recorded tree: the same differentiable arrays (materials, lights, textures,
    with ``vertices`` the points, with ``camera`` the camera and its rays made again in ``before``, with
    ``centres`` the area lights' sample points translated by their centres' moves, in ``before``) and a
    dielectric's ior, transmittance and absorption per material slot; ``then`` holds one launch of
    grad_tree's replay kernel per recorded level, each reading the rays its parent level wrote into their
    own arrays and adding its rays' colours to their camera rays' in ``rays``."""
    mats = geom.slot_materials(scene)
    vec = lambda rows: wp.array(np.asarray(rows, np.float32).reshape(-1, 3), dtype=wp.vec3, device=device,  # noqa: E731
                                requires_grad=True)
    ka, kd, ks, shininess, kr, light_pos, light_color, inverse_square, kind, axis, cone = replay_arrays(
        scene, geom, mats, device)
    ior = wp.array(np.asarray([m.ior or 0.0 for m in mats] or [0.0], np.float32), dtype=float, device=device,
                   requires_grad=True)
    kt = vec([m.transmittance for m in mats] or [[1, 1, 1]])
    sigma = vec([m.absorption for m in mats] or [[0, 0, 0]])
    n = hits.width * hits.height * hits.samples
    rays = wp.zeros(n, dtype=wp.vec3, device=device, requires_grad=True)
    points = wp.array(geom.points_np, dtype=wp.vec3, device=device, requires_grad=True) if vertices else geom.points
    cam = scene.camera
    eye = vec([geom.eye_offset(cam.eye), geom.eye_offset(cam.center), cam.up])
    fovy = wp.array([cam.fovy], dtype=float, device=device, requires_grad=True)
    dirs, before = hits.tree[0].dirs, []
    if camera:
        dirs = wp.zeros(n, dtype=wp.vec3, device=device, requires_grad=True)
        before.append((camera_rays, n, [eye, fovy, float(cam.near), hits.width, hits.height,
                                        math.isqrt(hits.samples), 1], [dirs]))
    normals = geom.normals
    if vertices and hits.smooth:  # a smooth object's vertex normals, computed from the moving points
        normals, launches = moving_normals(scene, geom, points, device)
        before += launches
    table = texture_table(mats, device)
    uvs = geom.uv_array() if hits.texture else wp.zeros(1, dtype=wp.vec2, device=device)
    common = [eye, points, geom.indices, normals, geom.tri_material, geom.tri_smooth, ka, kd, ks, shininess, kr,
              ior, kt, sigma, light_pos, light_color, inverse_square, kind, axis, cone, uvs, *table.arrays,
              wp.vec3(*scene.render.ambient), wp.vec3(*scene.render.background)]
    colors = vertex_colours(geom, hits, device)  # ka's and kd's factor, per vertex
    stand_in = wp.zeros(1, dtype=wp.vec3, device=device)
    o, w, start, then = stand_in, stand_in, stand_in, []
    area = hits.words > 0
    if area:
        a = hits.area  # the forward's own sample points, normals and areas
        first = a.first.numpy()
        sample_light = wp.array(np.repeat(np.arange(len(first) - 1), np.diff(first)).astype(np.int32), dtype=int,
                                device=device)
        radiance = vec([l.radiance for l in scene.area_lights])
        samples = a.points
        if centres:  # replay_launch's: the sample points moved with their light's centre (by 0 here)
            shift = wp.zeros(len(scene.area_lights), dtype=wp.vec3, device=device, requires_grad=True)
            samples = wp.zeros(int(first[-1]), dtype=wp.vec3, device=device, requires_grad=True)
            before.append((translate_samples, int(first[-1]), [a.points, sample_light, shift], [samples]))
    for i, level in enumerate(hits.tree):
        count = hits.tree[i + 1].count if i + 1 < len(hits.tree) else 0
        o_n, d_n, w_n, s_n = (wp.zeros(max(count, 1), dtype=wp.vec3, device=device, requires_grad=True)
                              for _ in range(4))
        # with area lights, the level's state for area_replay (stand-ins without)
        state = [wp.zeros(level.count if area else 1, dtype=wp.vec3, device=device, requires_grad=True)
                 for _ in range(7)]
        kernel = make_tree_replay_kernel(hits.lights, hits.smooth, hits.light_model, hits.texture, i == 0,
                                         hits.absorption, area, hits.vertex_color)
        then.append((kernel, level.count, [*common, level.face, level.visible, level.medium, level.ray_of, level.kind,
                                           level.child, o, dirs, w, start, rays, o_n, d_n, w_n, s_n, *state, colors],
                     []))
        if area:
            hit_p, hit_n, hit_kd, hit_ks, level_weight, acc, ray_dirs = state
            then.append((area_replay, (level.count, int(first[-1])),
                         [hits.words, level.face, ray_dirs, level.area_bits, geom.tri_material, shininess, hit_p,
                          hit_n, hit_kd, hit_ks, samples, a.normals, a.dA, sample_light, radiance], [acc]))
            then.append((tree_area_combine, level.count, [level.face, level.emit, radiance, level.ray_of,
                                                          level_weight, acc], [rays]))
        o, dirs, w, start = o_n, d_n, w_n, s_n
    arrays = {"ka": ka, "kd": kd, "ks": ks, "shininess": shininess, "reflectivity": kr, "color": light_color,
              "position": light_pos, "direction": axis, "texels": table.arrays[0], "ior": ior, "transmittance": kt,
              "absorption": sigma}
    if hits.vertex_color:
        arrays["colors"] = colors
    if area:
        arrays["radiance"] = radiance
        if centres:
            arrays["center"] = shift
    if vertices:
        arrays["points"] = points
    if camera:
        arrays["camera"], arrays["fovy"] = eye, fovy
    return ReplayLaunch(None, n, [], rays, arrays, table.images, then, rays, before)
