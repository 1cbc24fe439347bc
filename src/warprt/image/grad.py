"""Derivatives of an image (issue 30): Renderer.render(grad=True) records, per camera ray
(render.spp of them a pixel, where the trace kernel puts them) and ray level (the camera ray, then the
mirror rays the tracer follows), the hit and the lights it sees, as its own trace finds them (the trace
kernel's recording variant, kernels/record.py: no ray is traced twice); Renderer.backward(d_image, wrt) returns
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
give them: moving_normals), of the objects' poses (objects.<name>.translation and rotation: the points the
replay reads made from each object's rest points and (t, w) by kernels.posed_points ahead of the normals,
pose_points, the forward's points to the bit at the frame's pose), of the camera's eye, center, up and fovy
(the camera rays made again in Warp, kernels.camera_rays, and the hit recomputed on the recorded face from
the moved ray, through the mirror rays too), of the area lights' radiance (an area light's, an emitting
material's emission): their sample points' terms at each hit (the record's bit per point seen;
kernels.area_replay, one thread per level and point) and the emitter's front met by a ray, of a rectangle, disk or sphere light's centre (its sample
points translated by the centre's move, kernels.translate_samples, their normals and areas unchanged; an
object light's points, its shape and its emitting object's vertices held fixed), and of the vertex colours
(ka and kd times the colour interpolated at the hit's barycentrics, the moving ones where the hit moves;
kernels.vertex_colour: objects.<name>.colors) with every parameter above. The image is the mean of
each pixel's rays, as the trace kernel makes it. A parameter whose value switches its effect off keeps
its true derivative: a ks of 0 (the replay shades every Phong term), a light of colour 0 (its shadow rays
traced by the recording frame, grad_record.recording_effects: each such effect adds exactly 0 to the image), and a reflectivity of 0 where the caller names it, render(grad=[names]) recording
that material's mirror rays whatever its k_r (mirrored_materials; backward() refuses an unrecorded one in one
line rather than give it 0).

With glass (fx.refraction), Whitted's full ray tree (record_tree, replay_tree_launch; kernels/grad_tree.py):
the record, a kernel of its own still (the forward walks the tree depth first, the record lays it out level
by level), follows the forward's tree with the forward's own functions (each level's rays,
hits, visibility and children, the children compacted on the host into the next level's list), and the
replay is one differentiable launch per level, each level's rays in their own arrays (Warp replays neither
the forward's dynamic loop nor its in-place ray stack backwards). It differentiates a dielectric's ior,
transmittance and absorption through Fresnel, Snell and Beer, and everything above seen through the glass
(a reflectivity of 0 too, its mirror rays recorded as the chain's: mirror_anyway); held fixed besides the
faces and visibility: the tree's structure (which children exist, total internal reflection) and each ray's
medium. Its size is checked as it grows (_tree_too_big).

The record's layout and making are grad_record.py's, the parameters' names, refusals and gradients by name
grad_params.py's; this module replays a record on a wp.Tape (replay_launch, replay_tree_launch) and runs
backward().

With edges=True (the camera's silhouettes, occlusion edges and creases moving with the vertices and the
camera; with shadows, hard shadows' edges moving with them and with the lights), backward adds the boundary
term of the box-filtered pixel integral (grad_edges.py), where those are all the edges the named parameters
move (else refused naming ``edges``).

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
from ..kernels.grad import (TEXTURE_CHECKER, TEXTURE_CLAMP, TEXTURE_IMAGE, TEXTURE_MIRROR, TEXTURE_NONE, TEXTURE_WRAP,
                            area_replay, camera_rays, make_area_combine, make_grad_shade_kernel, posed_points,
                            sample_mean, smooth_vertex_normals, translate_samples, vertex_normal_sums)
from ..kernels.grad_tree import make_tree_replay_kernel, tree_area_combine
from ..geometry import LightShape, light_shape
from ..scene import drawn_objects, position_ids
from .grad_edges import EdgeFrame, check_edges, edge_gradients
from .grad_params import checked_names, gradients_by_name
from .grad_record import FirstHits, TreeHits
from .params import object_names, object_poses


@dataclass
class ReplayLaunch:
    """The differentiable replay of a recorded frame, ready to launch: kernels/grad.py's shade kernel
    over ``dim`` camera rays with ``inputs``, writing each ray's colour to ``rays``; ``arrays`` the
    inputs it differentiates, by key: ka, kd, ks, shininess, reflectivity per material slot, color,
    position and direction per Whitted light, radiance per area light, with vertices the geometry's
    points, with poses each object's translation and rotation, with vertex colours their per-vertex colors,
    with centres each area light's center (its shift). With area lights, the shade kernel writes each
    level's state (its ``rays`` a stand-in) and ``then`` holds the launches after it, (kernel, dim, inputs, outputs): the area lights' samples
    (kernels.area_replay) and the levels' sum into ``rays`` (make_area_combine)."""

    kernel: object
    dim: int
    inputs: list
    rays: wp.array
    arrays: dict
    images: dict  # TextureTable.images: where each textured colour's texels lie in arrays["texels"]
    then: list = None
    shaded: wp.array = None  # the shade kernel's output: ``rays`` without area lights
    before: list = None  # launches before the shade kernel's (camera_rays with the camera, posed_points with poses)


def replay(scene, geom, hits: FirstHits, device: str, vertices: bool = False, camera: bool = False,
           centres: bool = False, poses: list | None = None) -> ReplayLaunch:
    """replay_launch's kernels launched, on the current wp.Tape if there is one: its ``rays`` hold each
    camera ray's colour (one per pixel and sample)."""
    if isinstance(hits, TreeHits):
        r = replay_tree_launch(scene, geom, hits, device, vertices, camera, centres, poses)
    else:
        r = replay_launch(scene, geom, hits, device, vertices, camera, centres, poses)
    for kernel, dim, inputs, outputs in r.before or ():
        wp.launch(kernel, dim=dim, inputs=inputs, outputs=outputs, device=device)
    if r.kernel is not None:  # a tree's levels are all in ``then``
        wp.launch(r.kernel, dim=r.dim, inputs=r.inputs, outputs=[r.shaded], device=device)
    for kernel, dim, inputs, outputs in r.then or ():
        wp.launch(kernel, dim=dim, inputs=inputs, outputs=outputs, device=device)
    return r


def _vec3(rows, device: str) -> wp.array:
    """``rows`` as a differentiable float32 array of wp.vec3."""
    return wp.array(np.asarray(rows, np.float32).reshape(-1, 3), dtype=wp.vec3, device=device, requires_grad=True)


def replay_arrays(scene, geom, mats, device: str) -> tuple:
    """The replays' material and Whitted-light inputs (the chain's and the tree's), from the scene's values:
    per material slot (``mats``, geom.slot_materials) ka, kd, ks, shininess and reflectivity, per light its
    position, colour, falloff, kind, axis (unit, as Light keeps it: backward() projects its adjoint) and
    cone; the colours, exponents, positions and axes differentiable."""
    vec = lambda rows: _vec3(rows, device)  # noqa: E731
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


@dataclass
class ReplayScene:
    """What the chain's and the tree's replays read besides the record: replay_arrays' materials and lights,
    the points (differentiable with vertices; with poses made by posed_points) and vertex normals
    (moving_normals where they move), the camera (eye, center and up relative to the frame origin; fovy) and
    the camera rays' directions (the recorded ones, or made again by camera_rays with the camera), the texture
    table, the uvs and the vertex colours (vertex_colours); ``pose`` the objects' translations and rotations
    by ReplayLaunch.arrays' keys, with poses; ``before`` the launches that make the directions, points and
    normals."""

    ka: wp.array
    kd: wp.array
    ks: wp.array
    shininess: wp.array
    kr: wp.array
    light_pos: wp.array
    light_color: wp.array
    inverse_square: wp.array
    kind: wp.array
    axis: wp.array
    cone: wp.array
    mats: list  # geom.slot_materials
    points: wp.array
    normals: wp.array
    eye: wp.array
    fovy: wp.array
    dirs: wp.array
    table: TextureTable
    uvs: wp.array
    colors: wp.array
    before: list
    pose: dict

    def inputs(self, scene, geom, dielectric: tuple = ()) -> list:
        """The replay kernels' leading inputs, in their order: the geometry, the materials (with
        ``dielectric``, the tree's ior, k_t and sigma after them), the lights, the textures, ambient and
        background."""
        return [self.eye, self.points, geom.indices, self.normals, geom.tri_material, geom.tri_smooth, self.ka,
                self.kd, self.ks, self.shininess, self.kr, *dielectric, self.light_pos, self.light_color,
                self.inverse_square, self.kind, self.axis, self.cone, self.uvs, *self.table.arrays,
                wp.vec3(*scene.render.ambient), wp.vec3(*scene.render.background)]

    def arrays(self, vertex_color: bool, vertices: bool, camera: bool) -> dict:
        """The differentiable inputs by ReplayLaunch.arrays' keys."""
        out = {"ka": self.ka, "kd": self.kd, "ks": self.ks, "shininess": self.shininess, "reflectivity": self.kr,
               "color": self.light_color, "position": self.light_pos, "direction": self.axis,
               "texels": self.table.arrays[0]}
        if vertex_color:
            out["colors"] = self.colors
        if vertices:
            out["points"] = self.points
        out.update(self.pose)
        if camera:
            out["camera"], out["fovy"] = self.eye, self.fovy
        return out


def replay_scene(scene, geom, hits, device: str, vertices: bool, camera: bool, dirs: wp.array,
                 levels: int, poses: list | None = None) -> ReplayScene:
    """The ReplayScene of a recorded frame: ``dirs`` the camera rays' recorded directions; with ``camera``,
    made again instead, differentiable in the camera, by camera_rays (the first launch in ``before``),
    written every ``levels`` entries (the chain's record has ``levels`` a ray, the tree's first level one);
    with ``poses`` (params.Pose per scene object; with ``vertices``), the points made from them by
    posed_points (pose_points, in ``before`` ahead of the normals made from the points)."""
    mats = geom.slot_materials(scene)
    cam = scene.camera
    eye = _vec3([geom.eye_offset(cam.eye), geom.eye_offset(cam.center), cam.up], device)  # eye[0]: the rays' origin
    fovy = wp.array([cam.fovy], dtype=float, device=device, requires_grad=True)
    n, before = hits.width * hits.height * hits.samples, []
    if camera:  # the camera rays made again, differentiable in the camera, the recorded directions unused
        dirs = wp.zeros(n * levels, dtype=wp.vec3, device=device, requires_grad=True)
        before.append((camera_rays, n, [eye, fovy, float(cam.near), hits.width, hits.height,
                                        math.isqrt(hits.samples), levels], [dirs]))
    points, pose = geom.points, {}
    if poses is not None:  # the points made from the objects' poses, ahead of the normals made from them
        points, pose, launch = pose_points(scene, geom, poses, device)
        before.append(launch)
    elif vertices:
        points = wp.array(geom.points_np, dtype=wp.vec3, device=device, requires_grad=True)
    normals = geom.normals
    if vertices and hits.smooth:  # a smooth object's vertex normals, computed from the moving points
        normals, launches = moving_normals(scene, geom, points, device)
        before += launches
    uvs = geom.uv_array() if hits.texture else wp.zeros(1, dtype=wp.vec2, device=device)
    return ReplayScene(*replay_arrays(scene, geom, mats, device), mats=mats, points=points, normals=normals, eye=eye,
                       fovy=fovy, dirs=dirs, table=texture_table(mats, device), uvs=uvs,
                       colors=vertex_colours(geom, hits, device), before=before, pose=pose)


def pose_points(scene, geom, poses: list, device: str) -> tuple:
    """(points, arrays, launch): the replay's points made by posed_points from the forward's, each scene
    object's rest vertices and centre (params.Pose: relative to the frame origin in float64, then float32)
    and its pose (t0, w0; and t, w, differentiable: ``arrays``' translation and rotation, one row per object),
    the launch that makes them. ``points`` keeps its adjoint as the pose's is taken from it (retain_grad:
    Warp clears an array's adjoint once read backwards), the objects' vertices' gradient."""
    n = len(geom.points_np)
    owner = np.full(n, -1, np.int32)  # the area lights' own shapes (drawn_objects after the scene's) unposed
    rest = np.zeros((n, 3))
    base = 0
    for i, pose in enumerate(poses):
        owner[base:base + len(pose.rest)] = i
        rest[base:base + len(pose.rest)] = pose.rest - geom.origin
        base += len(pose.rest)
    rows = lambda key: np.asarray([getattr(x, key) for x in poses] or [np.zeros(3)], np.float64)  # noqa: E731
    vec = lambda a, grad=False: wp.array(np.asarray(a, np.float32).reshape(-1, 3), dtype=wp.vec3, device=device,  # noqa: E731
                                         requires_grad=grad)
    t, w = vec(rows("translation"), True), vec(rows("rotation"), True)
    points = wp.zeros(n, dtype=wp.vec3, device=device, requires_grad=True, retain_grad=True)
    inputs = [vec(geom.points_np), vec(rest), wp.array(owner, dtype=int, device=device),
              vec(rows("centre") - geom.origin), vec(rows("translation")), vec(rows("rotation")), t, w]
    return points, {"translation": t, "rotation": w}, (posed_points, n, inputs, [points])


@dataclass
class AreaSampleTable:
    """The area lights' sample points as area_replay reads them (``inputs``): the forward's own (the
    record's AreaLights table: points, normals, areas), each point's light, and per area light its
    radiance, differentiable; with centres, the points moved with their light's centre (c - c0, 0 here:
    the forward's points to the bit; their normals and areas as they are, a shape light's points being its
    centre plus fixed offsets) by translate_samples, the launch in ``before``, the shift differentiable."""

    points: wp.array
    normals: wp.array
    dA: wp.array
    light: wp.array
    radiance: wp.array
    count: int
    arrays: dict  # by ReplayLaunch.arrays' keys: radiance, and with centres center (the shift)
    before: list

    @property
    def inputs(self) -> list:
        """area_replay's inputs after the hits' state: the points, their normals, areas and lights, the radiance."""
        return [self.points, self.normals, self.dA, self.light, self.radiance]


def area_sample_table(scene, area, device: str, centres: bool) -> AreaSampleTable:
    """The AreaSampleTable of the recorded AreaLights table ``area``; with ``centres``, its points moving."""
    first = area.first.numpy()
    count = int(first[-1])
    light = wp.array(np.repeat(np.arange(len(first) - 1), np.diff(first)).astype(np.int32), dtype=int, device=device)
    radiance = _vec3([l.radiance for l in scene.area_lights], device)
    points, arrays, before = area.points, {"radiance": radiance}, []
    if centres:
        shift = wp.zeros(len(scene.area_lights), dtype=wp.vec3, device=device, requires_grad=True)
        points = wp.zeros(count, dtype=wp.vec3, device=device, requires_grad=True)
        before.append((translate_samples, count, [area.points, light, shift], [points]))
        arrays["center"] = shift
    return AreaSampleTable(points, area.normals, area.dA, light, radiance, count, arrays, before)


def replay_launch(scene, geom, hits: FirstHits, device: str, vertices: bool = False,
                  camera: bool = False, centres: bool = False, poses: list | None = None) -> ReplayLaunch:
    """The replay of ``hits`` (a frame of ``scene`` on ``geom``) with its differentiable arrays made from
    the scene's values; with ``vertices``, the points too (the hits recomputed on the moved faces); with
    ``camera``, the camera too: its eye, center and up (``arrays["camera"]``, the eye and
    center relative to the frame origin) and fovy, the camera rays' directions made from them (camera_rays,
    in ``before``) and the hits recomputed from the moved rays on the recorded faces; with ``centres`` (and area
    lights), the area lights' sample points translated by their centres' moves (``arrays["center"]``, 0:
    translate_samples, in ``before``), which the area lights' replay then reads; with ``poses`` (params.Pose
    per scene object, with ``vertices``), the points posed by the objects' translations and rotations
    (``arrays["translation"]``, ``arrays["rotation"]``: pose_points, in ``before``)."""
    sc = replay_scene(scene, geom, hits, device, vertices, camera, hits.dirs, hits.levels, poses)
    n, moving, area = hits.width * hits.height * hits.samples, vertices or camera, hits.words > 0
    kernel = make_grad_shade_kernel(hits.lights, hits.levels, hits.smooth, moving, hits.light_model, hits.texture,
                                    area, hits.vertex_color)
    rays = wp.zeros(n, dtype=wp.vec3, device=device, requires_grad=True)
    # each level's direction, as the moving replay makes it (vertices, camera): what the area lights' replay reads
    ray_dirs = wp.zeros(n * hits.levels if moving else 1, dtype=wp.vec3, device=device, requires_grad=True)
    levels = n * hits.levels if area else 1  # the area lights' per-level state (stand-ins without)
    state = [wp.zeros(levels, dtype=wp.vec3, device=device, requires_grad=True) for _ in range(6)]
    shaded = wp.zeros(1, dtype=wp.vec3, device=device, requires_grad=True) if area else rays
    inputs = [*sc.inputs(scene, geom), hits.face, hits.bary, sc.dirs, hits.visible, *state, ray_dirs, sc.colors]
    arrays, then = sc.arrays(hits.vertex_color, vertices, camera), []
    if area:
        table = area_sample_table(scene, hits.area, device, centres)
        sc.before += table.before
        arrays.update(table.arrays)
        hit_p, hit_n, hit_kd, hit_ks, level_weight, acc = state
        then.append((area_replay, (levels, table.count),
                     [hits.words, hits.face, ray_dirs if moving else sc.dirs, hits.area_bits, geom.tri_material,
                      sc.shininess, hit_p, hit_n, hit_kd, hit_ks, *table.inputs], [acc]))
        then.append((make_area_combine(hits.levels), n, [hits.face, hits.emit, table.radiance,
                                                         wp.vec3(*scene.render.background), level_weight, acc],
                     [rays]))
    return ReplayLaunch(kernel, n, inputs, rays, arrays, sc.table.images, then, shaded, sc.before)


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


def replay_image(scene, geom, hits: FirstHits, device: str, camera: bool = False, centres: bool = False,
                 poses: list | None = None) -> np.ndarray:
    """The image the replay makes of a recorded frame, (height, width, 3): the forward's, to float32
    rounding, where the replay models what the forward traced (what the tests check); with ``camera``, the
    replay camera gradients run (the rays made again from the camera, the hits re-intersected); with ``centres``,
    the area lights' sample points translated (by 0) as the replay of their centres' gradients does; with
    ``poses`` (params.Pose per scene object), the points posed as the replay of the poses' gradients poses them."""
    rays = replay(scene, geom, hits, device, vertices=poses is not None, camera=camera, centres=centres,
                  poses=poses).rays
    image = wp.empty(hits.width * hits.height, dtype=wp.vec3, device=device)
    wp.launch(sample_mean, dim=hits.width * hits.height, inputs=[rays, hits.samples], outputs=[image], device=device)
    return image.numpy().reshape(hits.height, hits.width, 3)


def backward(scene, geom, hits: FirstHits, d_image, wrt, device: str, poses: list | None = None,
             edges: bool = False, frame: EdgeFrame | None = None) -> dict:
    """{name: d(sum(d_image * image)) / d(param)} for each name in ``wrt`` (parameter_names), each shaped
    as the parameter: (3,) for colours, positions and poses, () for an exponent. ``poses``: params.Pose per
    scene object (the Renderer's, object_poses), read where ``wrt`` names a translation or rotation. With
    ``edges``, the boundary term of the edges camera rays see added (grad_edges.py; ``frame``: the frame's
    EdgeFrame; a pose's through its vertices' and the pose's Jacobian, pose_edge_gradients), where those are
    all the edges the parameters move (else one ArgumentError naming ``edges``: check_edges)."""
    wrt = checked_names(scene, geom, hits, wrt)
    if edges:
        check_edges(scene, geom, frame, hits, wrt)
    d = np.asarray(d_image.numpy() if isinstance(d_image, wp.array) else d_image, np.float32)
    if d.shape != (hits.height, hits.width, 3) or not np.all(np.isfinite(d)):
        raise ArgumentError("backward", "d_image", f"expected finite values of shape {(hits.height, hits.width, 3)}, "
                                                   f"got {d.shape}")
    posing = any(name.startswith("objects.") and name.endswith((".translation", ".rotation")) for name in wrt)
    moving = posing or any(name.startswith("objects.") and name.endswith(".vertices") for name in wrt)
    camera = any(name.startswith("camera.") for name in wrt)
    centres = any(name.startswith("lights.") and name.endswith(".center") for name in wrt)
    if posing and poses is None:
        poses = object_poses(scene, {})
    tape = wp.Tape()
    with tape:
        launched = replay(scene, geom, hits, device, moving, camera, centres, poses if posing else None)
    # The image is the mean of each pixel's rays (sample_mean): its adjoint, d_image / samples to each ray.
    d_rays = np.repeat(d.reshape(-1, 3), hits.samples, axis=0) / np.float32(hits.samples)
    tape.backward(grads={launched.rays: wp.array(d_rays, dtype=wp.vec3, device=device)})
    out = gradients_by_name(scene, geom, launched, wrt)
    tape.zero()
    if edges:
        # One pass over the edges for every name: a pose's term is its vertices' taken back through the pose.
        posed = sorted({n.split(".")[1] for n in wrt if n.startswith("objects.") and n.endswith((".translation",
                                                                                                  ".rotation"))})
        terms = edge_gradients(scene, geom, frame, d, list(dict.fromkeys(
            list(wrt) + [f"objects.{o}.vertices" for o in posed])), device)
        if posing:
            terms.update(pose_edge_gradients(scene, geom, terms, wrt, device, poses))
        for name in wrt:
            if name in terms:
                out[name] = out[name] + terms[name]
    return out


def pose_edge_gradients(scene, geom, vertex_terms: dict, wrt, device: str, poses: list) -> dict:
    """The edges' term of each translation and rotation in ``wrt``: the edge term of its object's vertices
    (``vertex_terms``, grad_edges.edge_gradients' by name) taken back through the pose (pose_points'
    posed_points, on a tape of its own, its adjoint the vertices' edge term), as the interior term is."""
    posed = [n for n in wrt if n.startswith("objects.") and n.endswith((".translation", ".rotation"))]
    index = object_names(scene)
    owners = sorted({n.split(".")[1] for n in posed})
    adjoint = np.zeros((len(geom.points_np), 3), np.float32)
    starts = np.cumsum([0] + [len(o.vertices) for o in scene.objects])
    for o in owners:
        i = index[o]
        adjoint[starts[i]:starts[i + 1]] = vertex_terms[f"objects.{o}.vertices"]
    points, arrays, (kernel, dim, inputs, outputs) = pose_points(scene, geom, poses, device)
    tape = wp.Tape()
    with tape:
        wp.launch(kernel, dim=dim, inputs=inputs, outputs=outputs, device=device)
    tape.backward(grads={points: wp.array(adjoint, dtype=wp.vec3, device=device)})
    out = {n: arrays[n.split(".")[2]].grad.numpy()[index[n.split(".")[1]]].astype(np.float64) for n in posed}
    tape.zero()
    return out


# --- Glass: Whitted's full ray tree (kernels/grad_tree.py) --------------------------------------------------

def replay_tree_launch(scene, geom, hits: TreeHits, device: str, vertices: bool = False,
                       camera: bool = False, centres: bool = False, poses: list | None = None) -> ReplayLaunch:
    """replay_launch for a recorded tree: the same differentiable arrays (materials, lights, textures,
    with ``vertices`` the points, with ``poses`` made from the objects' poses, with ``camera`` the camera and
    its rays made again in ``before``, with ``centres`` the area lights' sample points translated by their
    centres' moves, in ``before``) and a
    dielectric's ior, transmittance and absorption per material slot; ``then`` holds one launch of
    grad_tree's replay kernel per recorded level, each reading the rays its parent level wrote into their
    own arrays and adding its rays' colours to their camera rays' in ``rays``."""
    sc = replay_scene(scene, geom, hits, device, vertices, camera, hits.tree[0].dirs, 1, poses)
    ior = wp.array(np.asarray([m.ior or 0.0 for m in sc.mats] or [0.0], np.float32), dtype=float, device=device,
                   requires_grad=True)
    kt = _vec3([m.transmittance for m in sc.mats] or [[1, 1, 1]], device)
    sigma = _vec3([m.absorption for m in sc.mats] or [[0, 0, 0]], device)
    n = hits.width * hits.height * hits.samples
    rays = wp.zeros(n, dtype=wp.vec3, device=device, requires_grad=True)
    common = sc.inputs(scene, geom, (ior, kt, sigma))
    arrays = {**sc.arrays(hits.vertex_color, vertices, camera), "ior": ior, "transmittance": kt, "absorption": sigma}
    area = hits.words > 0
    if area:
        table = area_sample_table(scene, hits.area, device, centres)
        sc.before += table.before
        arrays.update(table.arrays)
    stand_in = wp.zeros(1, dtype=wp.vec3, device=device)
    o, dirs, w, start, then = stand_in, sc.dirs, stand_in, stand_in, []
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
                                           level.child, o, dirs, w, start, rays, o_n, d_n, w_n, s_n, *state, sc.colors],
                     []))
        if area:
            hit_p, hit_n, hit_kd, hit_ks, level_weight, acc, ray_dirs = state
            then.append((area_replay, (level.count, table.count),
                         [hits.words, level.face, ray_dirs, level.area_bits, geom.tri_material, sc.shininess, hit_p,
                          hit_n, hit_kd, hit_ks, *table.inputs], [acc]))
            then.append((tree_area_combine, level.count, [level.face, level.emit, table.radiance, level.ray_of,
                                                          level_weight, acc], [rays]))
        o, dirs, w, start = o_n, d_n, w_n, s_n
    return ReplayLaunch(None, n, [], rays, arrays, sc.table.images, then, rays, sc.before)
