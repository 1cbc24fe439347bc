"""Derivatives of an image (issue 30): Renderer.render(grad=True) records, as its own trace finds them, every ray
of the frame's ray tree (per camera ray, render.spp of them a pixel: the camera ray, the mirror rays, glass's
reflected and refracted rays), its hit and the lights it sees (the trace kernel's recording variant,
kernels/record.py; grad_record.py lays it out); Renderer.backward(d_image, wrt) returns d(sum(d_image * image))
/ d(param) for the parameters named as r.params names them, through the replay of that record with the
forward's own functions (kernels/replay.py) on a wp.Tape, one launch a ray level: one tracer for the image and
its derivative.

What is differentiated, and what is held: each ray's face and the visibility of each light are held fixed, as a
visibility-fixed derivative is (an edge or a shadow's edge moving across pixels has no derivative here; edges=True
adds that of the edges camera rays see and of hard shadows' edges, grad_edges.py), and so are which rays the tree has (total internal
reflection, a child carrying nothing) and each ray's medium. Everything the forward computes from the parameters
at those hits is differentiated as the forward computes it, because it is the forward's code: the material
colours and exponents (with their textures' texels: the forward's bilinear lookup over SceneData.texels, each
image colour its own copy here so that each gets its own adjoint; and the vertex colours), the lights' colours,
positions and directions (a spot's cone, 1 / r^2 falloff), the area lights' radiance (an area light's, an
emitting material's emission) through their sample points and the emitter a ray meets, a rectangle, disk or
sphere light's own shape (its center, normal, size or radius, or a rectangle's half-edges: its sample points,
normals and areas moved with it, grad_area_shape.moving_samples; an object light's points and its emitting
object's vertices held fixed), a
mirror's reflectivity (at 0 too, where render(grad=[that name]) followed its rays with weight 0:
grad_params.mirrored_materials; backward() refuses an unrecorded one in one line rather than give it 0), a
dielectric's ior, transmittance and absorption (Fresnel, Snell and Beer, through the whole ray tree; a
transmittance of 0's refracted rays followed with weight 0, their radiance its derivative), the objects' vertices
and poses (the hit recomputed on the moved face from the moving ray, through the mirror and glass rays too,
each spawned from the moved hit; a smooth object's vertex normals made again from the moving points as the
forward's Geometry makes them, kernels.vertex_normal_sums and smooth_vertex_normals, where the scene does not give
them: moving_normals; an object's translation and rotation through kernels.posed_points, pose_points, the
forward's points to the bit at the frame's pose), and the camera's eye, center, up and fovy (the camera rays made
again by the forward's camera_ray from a basis made in Warp, kernels.camera_of, the hits recomputed from them).
The image is the mean of each pixel's rays, as the trace kernel makes it. A parameter whose value switches its
effect off keeps its true derivative: the replay shades every Phong term (a ks of 0), and the recording frame
traces what adds exactly 0 to the image but not to its derivative (grad_record.recording_effects: a light of
colour 0's shadow rays, the light loop where kd and ks are 0).

The record's layout and making are grad_record.py's, the parameters' names, refusals and gradients by name
grad_params.py's; this module builds the replay (build_replay), launches it on a wp.Tape (Replay.launch) and runs
backward(). Covered: any render.spp and light_samples, camera, mirror and glass rays, image and checker textures,
vertex colours, area lights; any other scene is refused in one line naming what is not yet differentiated, so a
gradient is never silently partial.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._warp import wp
from ..errors import ArgumentError
from ..geometry import AreaLights, SceneData, TextureSlot, texel_array, texture_slots
from ..kernels import (NO_RAY, ReplayCamera, ReplayHits, ReplayRays, camera_data, make_replay_combine, make_replay_level,
                       posed_points, replay_area, sample_mean)
from ..kernels.interaction import Surface
from ..kernels.shading import Coefficients
from ..scene import camera_basis, drawn_objects
from .grad_area_shape import SHAPE_KEYS, moving_samples, shape_table
from .grad_edges import EdgeFrame, check_edges, edge_gradients
from .grad_normals import moving_normals
from .grad_params import checked_names, gradients_by_name
from .grad_record import Record
from .params import object_names, object_poses


@dataclass
class Replay:
    """A recorded frame's replay, ready to launch (on a wp.Tape): ``data``, the frame's SceneData with the
    parameters' arrays copied in, differentiable (what the gradient is taken of), ``camera`` the camera rays'
    (ReplayCamera), ``rays`` and ``hits`` what a level's launch hands the next and the area lights' (stand-ins
    where not needed), ``colour`` each camera ray's colour (one per pixel and sample, as recorded); ``before``
    the launches (kernel, dim, inputs, outputs) that make the moving inputs first (posed points, vertex normals,
    the area lights' translated points); ``arrays`` the differentiable inputs by key (ka, kd, ks, shininess,
    reflectivity, ior, transmittance, absorption per material slot; color, position per Whitted light and
    direction, its LightShape's; texels; radiance per area light; with vertices the points, with poses each
    object's translation and rotation, with vertex colours the colors, with shapes the shape lights' parameters
    (``shape``: grad_area_shape.ShapeTable),
    with the camera the camera and fovy); ``images`` where each image colour's texels lie in ``texels``."""

    hits: Record
    data: SceneData
    camera: ReplayCamera
    rays: ReplayRays
    area: ReplayHits
    colour: wp.array
    sample_light: wp.array
    arrays: dict
    images: dict
    before: list
    moving: bool
    camera_moves: bool
    device: str
    area_kernel: object = replay_area  # what adds the area lights' sample points (a test's control swaps it)
    focus: np.ndarray | None = None  # per camera ray, whether its tree is launched (replay_focus; None: every one)

    def launch(self):
        """The replay's launches, in order: ``before``, then per recorded level its kernel (and with area
        lights replay_area and replay_combine): ``colour`` holds each camera ray's colour after."""
        h, device = self.hits, self.device
        for kernel, dim, inputs, outputs in self.before:
            wp.launch(kernel, dim=dim, inputs=inputs, outputs=outputs, device=device)
        for k, live in enumerate(live_entries(h, device, self.focus)):
            if live is None:
                continue
            moving = self.moving or (k > 0 and h.fx.refraction)  # a refracted ray turns with the ior
            kernel = make_replay_level(h.fx, h.lights, k == 0, moving, self.camera_moves and k == 0, h.absorption)
            count = live.shape[0]
            wp.launch(kernel, dim=count, inputs=[self.data, self.camera, h.rec, live, self.rays, self.area],
                      outputs=[self.colour], device=device)
            if h.words:
                wp.launch(self.area_kernel, dim=(count, int(self.sample_light.shape[0])),
                          inputs=[self.data, h.rec, live, self.sample_light, self.area], device=device)
                wp.launch(make_replay_combine(h.tree), dim=count, inputs=[h.rec, live, self.area],
                          outputs=[self.colour], device=device)


def _vec3(rows, device: str, grad: bool = True) -> wp.array:
    """``rows`` as a float32 array of wp.vec3, differentiable (``grad``)."""
    return wp.array(np.asarray(rows, np.float32).reshape(-1, 3), dtype=wp.vec3, device=device, requires_grad=grad)


def live_entries(hits: Record, device: str, focus: np.ndarray | None = None) -> list:
    """Per recorded level the entries a ray reached (its face not NO_RAY), ascending, as an int wp.array (None
    where none did): what the replay launches over; with ``focus`` (per camera ray, replay_focus) only those of
    the camera rays it keeps. A mirror chain's deeper levels and glass's regions are mostly
    places no ray reached (scenes/mirrors.toml at 512x384: 45% of level 1's, 1% of level 7's reached), and an
    adjoint thread costs even where its entry is empty. In ascending order the CPU's threads add to the colours
    and the adjoints in the order the whole level's would: the same sums to the bit."""
    face, out = hits.rec.face.numpy(), []
    ray = None if focus is None else entry_rays(hits)
    for k in range(hits.levels):
        first, count = hits.level(k)
        reached = face[first:first + count] != NO_RAY
        if focus is not None:
            reached &= focus[ray[first:first + count]]
        live = np.flatnonzero(reached).astype(np.int32) + np.int32(first)
        out.append(wp.array(live, dtype=int, device=device) if len(live) else None)
    return out


def entry_rays(hits: Record) -> np.ndarray:
    """Per entry of the record its camera ray (kernels/record.py make_entry's entry_ray: a chain's from its place,
    glass's as written; 0 where no ray reached it)."""
    if not hits.tree:
        return np.arange(hits.entries) % hits.camera_rays
    ray = hits.rec.ray_of.numpy()[:hits.entries].copy()
    ray[hits.rec.face.numpy()[:hits.entries] == NO_RAY] = 0
    return ray


OBJECT_KEYS = ("vertices", "translation", "rotation", "colors")


def replay_focus(scene, hits: Record, wrt, d: np.ndarray) -> np.ndarray:
    """Per camera ray, whether the replay launches its ray tree for the gradients of ``wrt`` against ``d`` (the
    image's adjoint): not where its pixel's adjoint is 0, and where every name is an object's (its vertices, pose
    or vertex colours) only where the tree meets a face of those objects. The derivative of a pixel in those
    parameters, its faces and its lights' answers held, is the sum over its rays at the objects' faces of what
    they shade there and what they spawn: a tree that never meets them adds exactly 0, the trees kept add what
    they did in the order they did (live_entries), and the gradients are the same to the bit (checked). A pose's
    pixels are a fraction of the frame (tests/grad/test_replay_focus.py: what each scene keeps)."""
    keep = np.repeat((d.reshape(-1, 3) != 0).any(axis=1), hits.samples)
    names = [n for n in wrt if n.startswith("objects.") and n.rsplit(".", 1)[1] in OBJECT_KEYS]
    if len(names) < len(wrt):
        return keep
    index = object_names(scene)
    starts = np.cumsum([0] + [len(o.faces) for o in drawn_objects(scene)])
    named = np.zeros(int(starts[-1]) + 1, bool)  # the last for a face no drawn object has (a miss: -1)
    for n in names:
        i = index[n[len("objects."):n.rindex(".")]]
        named[starts[i]:starts[i + 1]] = True
    face = hits.rec.face.numpy()[:hits.entries]
    meets = named[np.where((face >= 0) & (face < len(named) - 1), face, len(named) - 1)]
    trees = np.zeros(hits.camera_rays, bool)
    trees[entry_rays(hits)[meets]] = True
    return keep & trees


def pooled_zeros(hits: Record, key: str, n: int, dtype, device: str) -> wp.array:
    """``n`` zeros of ``dtype``, differentiable (their adjoint zero too): the array ``key`` of the record's pool
    (Record.pool) zeroed again where the last replay of this record, or of the last grad frame's, left one of this
    size, else a new one kept there. The replay's per-entry arrays are tens of MB, and a new one costs its pages
    each time (a warm backward of scenes/seed.toml at 512x384: 17 ms of 150)."""
    a = hits.pool.get(key)
    if a is None or a.shape != (n,) or a.dtype != dtype or a.device != wp.get_device(device):
        a = hits.pool[key] = wp.zeros(n, dtype=dtype, device=device, requires_grad=True)
    else:
        a.zero_()
        a.grad.zero_()
    return a


def _copy(a: wp.array) -> wp.array:
    """A differentiable copy of the frame's array ``a``: its very values, with an adjoint of its own."""
    return wp.array(a.numpy(), dtype=a.dtype, device=a.device, requires_grad=True)


def _struct(value, cls):
    """A new instance of the Warp struct ``cls`` holding ``value``'s fields."""
    out = cls()
    for name in cls.vars:
        setattr(out, name, getattr(value, name))
    return out


def build_replay(scene, geom, hits: Record, device: str, vertices: bool = False, camera: bool = False,
                 shapes: bool = False, poses: list | None = None) -> Replay:
    """The Replay of ``hits`` (a frame of ``scene`` on ``geom``): the frame's SceneData with its materials', lights',
    textures' and area lights' arrays copied, differentiable; with ``vertices`` its points too (the hits recomputed
    on the moved faces, a smooth object's normals made from the points, moving_normals); with ``poses``
    (params.Pose per scene object, with ``vertices``) the points posed by the objects' translations and rotations
    (pose_points); with ``camera`` its eye, center, up and fovy (the camera rays made from them, the hits
    recomputed from the moved rays); with ``shapes`` (and area lights) the area lights' sample points, normals and
    areas moving with their shape lights' centers, normals, sizes and radii (the forward's at the frame's values)."""
    data, mats, before = _struct(hits.data, SceneData), geom.slot_materials(scene), []
    for key in ("ka", "kd", "ks", "kr", "shininess", "ior", "transmittance", "absorption", "light_pos",
                "light_color", "light_shape"):
        setattr(data, key, _copy(getattr(hits.data, key)))
    slots, images, placed = texture_slots(mats, per_use=True)
    data.texels = texel_array(images, device, requires_grad=True)
    data.ka_map, data.kd_map, data.ks_map = (wp.array(slots[k], dtype=TextureSlot, device=device)
                                             for k in ("ka", "kd", "ks"))
    if hits.fx.vertex_color:
        data.colors = _copy(geom.colors)
    arrays = {"ka": data.ka, "kd": data.kd, "ks": data.ks, "shininess": data.shininess, "reflectivity": data.kr,
              "ior": data.ior, "transmittance": data.transmittance, "absorption": data.absorption,
              "color": data.light_color, "position": data.light_pos, "direction": data.light_shape,
              "texels": data.texels, "colors": data.colors}
    if poses is not None:  # the points made from the objects' poses, ahead of the normals made from them
        data.points, pose, launch = pose_points(scene, geom, poses, device)
        arrays.update(pose)
        before.append(launch)
    elif vertices:  # the objects' vertices (geom.points holds the BVH's padding points after them)
        data.points = _vec3(geom.points_np, device)
    if vertices:
        arrays["points"] = data.points
        if hits.fx.smooth:  # a smooth object's vertex normals, computed from the moving points
            data.normals, launches = moving_normals(scene, geom, data.points, device)
            before += launches
    sample_light = wp.zeros(1, dtype=int, device=device)
    if hits.words:
        data.area, sample_light, area_arrays, launches = area_replay_table(scene, geom, hits, device, shapes)
        arrays.update(area_arrays)
        before += launches
    cam = replay_camera(scene, geom, hits, device)
    arrays["camera"], arrays["fovy"] = cam.camera, cam.fovy
    return Replay(hits, data, cam, replay_rays(hits, vertices or camera or hits.fx.refraction, device),
                  replay_hits(hits, device),
                  pooled_zeros(hits, "colour", hits.camera_rays, wp.vec3, device), sample_light, arrays,
                  placed, before, vertices or camera, camera, device)


def replay_camera(scene, geom, hits: Record, device: str) -> ReplayCamera:
    """The ReplayCamera of a frame: its eye and center relative to the frame origin (the forward's float32 eye, the
    camera rays' origin: ``origin`` is that array) and up, and fovy, differentiable."""
    cam = scene.camera
    c = ReplayCamera()
    c.frame = camera_data(camera_basis(cam), geom.eye_offset(cam.eye))
    c.camera = _vec3([geom.eye_offset(cam.eye), geom.eye_offset(cam.center), cam.up], device)
    c.origin = c.camera
    c.fovy = wp.array([cam.fovy], dtype=float, device=device, requires_grad=True)
    c.near, c.k = float(cam.near), int(round(np.sqrt(hits.samples)))
    return c


def replay_rays(hits: Record, moving: bool, device: str) -> ReplayRays:
    """The arrays a level's launch hands the next (ReplayRays): a child's weight and direction (two a ray with
    glass), with ``moving`` (the hits move, or glass) its origin, with Beer's law where each ray began; stand-ins
    for what is not read."""
    n = hits.entries * (2 if hits.fx.refraction else 1) if hits.levels > 1 else 1
    zeros = lambda key, size: pooled_zeros(hits, key, max(size, 1), wp.vec3, device)  # noqa: E731
    r = ReplayRays()
    r.weight, r.direction = zeros("weight", n), zeros("direction", n)
    r.origin = zeros("origin", n if moving else 1)
    r.start = zeros("start", hits.entries if hits.absorption and hits.levels > 1 else 1)
    return r


def replay_hits(hits: Record, device: str) -> ReplayHits:
    """With area lights, what the area lights' replay reads of each entry (ReplayHits); stand-ins without."""
    n = hits.entries if hits.words else 1
    h = ReplayHits()
    h.hit = pooled_zeros(hits, "hit", n, Surface, device)
    h.k = pooled_zeros(hits, "k", n, Coefficients, device)
    h.direction, h.weight, h.local = (pooled_zeros(hits, f"hits.{key}", n, wp.vec3, device)
                                      for key in ("direction", "weight", "local"))
    return h


def area_replay_table(scene, geom, hits: Record, device: str, shapes: bool) -> tuple:
    """(area, sample_light, arrays, launches): the frame's area lights (AreaLights) with their radiance copied,
    differentiable, and with ``shapes`` their sample points, normals and areas moving with their shape lights'
    centers, normals, sizes and radii (grad_area_shape.moving_samples: the forward's at the frame's values, to the
    bit), the launch that makes them; each point's light."""
    area = hits.data.area
    first = area.first.numpy()
    light = wp.array(np.repeat(np.arange(len(first) - 1), np.diff(first)).astype(np.int32), dtype=int, device=device)
    out = _struct(area, AreaLights)
    out.radiance = _copy(area.radiance)
    arrays, launches = {"radiance": out.radiance}, []
    if shapes:
        table = shape_table(scene, geom, device)
        k = int(round(np.sqrt(scene.render.light_samples)))
        out.points, out.normals, out.dA, launch = moving_samples(scene, area, table, k, device)
        launches.append(launch)
        arrays["shape"] = table
    return out, light, arrays, launches


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
    t, w = _vec3(rows("translation"), device), _vec3(rows("rotation"), device)
    points = wp.zeros(n, dtype=wp.vec3, device=device, requires_grad=True, retain_grad=True)
    inputs = [_vec3(geom.points_np, device, False), _vec3(rest, device, False),
              wp.array(owner, dtype=int, device=device), _vec3(rows("centre") - geom.origin, device, False),
              _vec3(rows("translation"), device, False), _vec3(rows("rotation"), device, False), t, w]
    return points, {"translation": t, "rotation": w}, (posed_points, n, inputs, [points])


def replay_image(scene, geom, hits: Record, device: str, camera: bool = False, shapes: bool = False,
                 poses: list | None = None) -> np.ndarray:
    """The image the replay makes of a recorded frame, (height, width, 3): the forward's, to float32
    rounding, where the replay models what the forward traced (what the tests check); with ``camera``, the
    replay camera gradients run (the rays made again from the camera, the hits re-intersected); with ``shapes``,
    the area lights' sample points moved (by 0) as the replay of their shapes' gradients moves them; with
    ``poses`` (params.Pose per scene object), the points posed as the replay of the poses' gradients poses them."""
    replay = build_replay(scene, geom, hits, device, vertices=poses is not None, camera=camera, shapes=shapes,
                          poses=poses)
    replay.launch()
    image = wp.empty(hits.width * hits.height, dtype=wp.vec3, device=device)
    wp.launch(sample_mean, dim=hits.width * hits.height, inputs=[replay.colour, hits.samples], outputs=[image],
              device=device)
    return image.numpy().reshape(hits.height, hits.width, 3)


def backward(scene, geom, hits: Record, d_image, wrt, device: str, poses: list | None = None,
             edges: bool = True, frame: EdgeFrame | None = None) -> dict:
    """{name: d(sum(d_image * image)) / d(param)} for each name in ``wrt`` (parameter_names), each shaped
    as the parameter: (3,) for colours, positions and poses, () for an exponent. ``poses``: params.Pose per
    scene object (the Renderer's, object_poses), read where ``wrt`` names a translation or rotation. With
    ``edges``, the boundary term of the edges camera rays see added (grad_edges.py; ``frame``: the frame's
    EdgeFrame; a pose's through its vertices' and the pose's Jacobian, pose_edge_gradients), where those are
    all the edges the parameters move (else one ArgumentError naming ``edges``: check_edges)."""
    wrt = checked_names(scene, geom, hits, wrt)
    d = np.asarray(d_image.numpy() if isinstance(d_image, wp.array) else d_image, np.float32)
    if d.shape != (hits.height, hits.width, 3) or not np.all(np.isfinite(d)):
        raise ArgumentError("backward", "d_image", f"expected finite values of shape {(hits.height, hits.width, 3)}, "
                                                   f"got {d.shape}")
    if edges:
        check_edges(scene, geom, frame, wrt)
    posing = any(name.startswith("objects.") and name.endswith((".translation", ".rotation")) for name in wrt)
    moving = posing or any(name.startswith("objects.") and name.endswith(".vertices") for name in wrt)
    camera = any(name.startswith("camera.") for name in wrt)
    shapes = any(name.startswith("lights.") and name.endswith(tuple(f".{k}" for k in SHAPE_KEYS)) for name in wrt)
    if posing and poses is None:
        poses = object_poses(scene, {})
    replay = build_replay(scene, geom, hits, device, moving, camera, shapes, poses if posing else None)
    replay.focus = replay_focus(scene, hits, wrt, d)
    tape = wp.Tape()
    with tape:
        replay.launch()
    # The image is the mean of each pixel's rays (sample_mean): its adjoint, d_image / samples to each ray.
    d_rays = np.repeat(d.reshape(-1, 3), hits.samples, axis=0) / np.float32(hits.samples)
    tape.backward(grads={replay.colour: wp.array(d_rays, dtype=wp.vec3, device=device)})
    out = gradients_by_name(scene, geom, replay, wrt)
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
