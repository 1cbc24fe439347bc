"""The derivative of a frame (launched by image/grad.py): its record (kernels/record.py) replayed on a wp.Tape, one
launch a ray level, with the forward's own functions, so that the image and its derivative are one tracer.

Each entry's ray is made again: at level 0 the camera's (camera_ray; with the camera differentiated, its basis
made in Warp by camera_of), deeper the child its parent's launch left (a mirror's bounce, mirror_ray, weighted
by k_r; a dielectric's reflected and refracted rays, dielectric_children: Fresnel, Snell, k_t). Its hit is on
the recorded face, at the recorded barycentrics or, where the geometry or the camera moves, where the moving
ray meets the face (barycentrics_on); make_surface makes the hit record from it and absorbed weighs the segment
(Beer). Its colour is the forward's: the background where it met nothing, the radiance of the area light it
met (recorded), the ambient term and each Whitted light the record saw (light_arrival, whitted_term, the
lights unrolled: Warp replays no dynamic loop backwards), with area lights each sample point the record saw
(replay_area: area_arrival, area_term, one thread per entry and point); each added to its camera ray's by
wp.atomic_add (on the CPU in order: a chain's sums are the forward's). What is held fixed is what the record
holds: each ray's face, each shadow ray's answer, which rays the tree has, each ray's medium.
"""

from __future__ import annotations

import functools

from .._warp import wp
from ..geometry import SceneData
from .camera import CameraData, camera_of, camera_ray, sample_offset
from .dielectric import absorbed, absorbed_forever, dielectric_children
from .interaction import Ray, Surface, make_surface, mirror_ray, spawn_ray
from .record import NO_RAY, GradRecord, make_entry, make_follows_mirror
from .shading import Coefficients, area_arrival, make_coefficients, make_light_arrival, make_light_terms
from .triangle import query_normal, triangle

MAX_GRAD_LIGHTS = 16  # Warp's max_unroll: the replay's lights loop, longer, would silently turn dynamic


@wp.struct
class ReplayCamera:
    """The camera the replay's camera rays start from: ``frame`` the forward's (its basis as the host made it, the
    rays the same to the bit); ``camera`` its eye and center (relative to the frame origin) and up, ``fovy`` in
    degrees, differentiable, which make the rays where the camera is differentiated; the rays' ``origin``, the
    eye (``camera`` itself: its first row); the image and its ``k`` x ``k`` samples a pixel."""

    frame: CameraData
    camera: wp.array(dtype=wp.vec3)
    origin: wp.array(dtype=wp.vec3)
    fovy: wp.array(dtype=float)
    near: float
    width: int
    height: int
    k: int


@wp.struct
class ReplayRays:
    """What a level's launch hands the next: per child (entry x branches + branch) its weight and direction, and
    where the hits move its origin; per entry its hit point, where its children's segments begin (Beer)."""

    weight: wp.array(dtype=wp.vec3)
    origin: wp.array(dtype=wp.vec3)
    direction: wp.array(dtype=wp.vec3)
    start: wp.array(dtype=wp.vec3)


@wp.struct
class ReplayHits:
    """With area lights, per entry what replay_area and replay_combine read: its hit, colours, direction and
    weight, and its local colour, to which the sample points seen are added."""

    hit: wp.array(dtype=Surface)
    k: wp.array(dtype=Coefficients)
    direction: wp.array(dtype=wp.vec3)
    weight: wp.array(dtype=wp.vec3)
    local: wp.array(dtype=wp.vec3)


@wp.func
def barycentrics_on(p0: wp.vec3, p1: wp.vec3, p2: wp.vec3, o: wp.vec3, d: wp.vec3) -> wp.vec2:
    """Where the ray o + t d meets the plane of the triangle (p0, p1, p2), as (u, v) in Warp's convention (u
    weighs p0, v p1): Moller-Trumbore, differentiable in the points and the ray, without its inside test
    (the face is the recorded one). The replay's hit on a moved face or from a moved ray."""
    e1 = p1 - p0
    e2 = p2 - p0
    pv = wp.cross(d, e2)
    inv = 1.0 / wp.dot(e1, pv)
    tv = o - p0
    b1 = wp.dot(tv, pv) * inv
    b2 = wp.dot(d, wp.cross(tv, e1)) * inv
    return wp.vec2(1.0 - b1 - b2, b1)


@functools.cache
def make_replay_ray(TREE: bool, FIRST: bool, MOVING: bool, CAMERA: bool, ABSORB: bool):
    """replay_ray(cam, rec, rays, j) -> (o, d, weight, start): entry j's ray as its level's launch makes it
    again: a camera ray (FIRST: the forward's camera_ray, or with CAMERA the differentiable camera's), else its
    parent's child (its weight and direction, and with MOVING its origin, from ``rays``: make_entry says which);
    ``start`` where its segment began (ABSORB)."""
    entry_parent, _, _ = make_entry(TREE)
    BRANCHES = 2 if TREE else 1

    @wp.func
    def replay_ray(cam: ReplayCamera, rec: GradRecord, rays: ReplayRays, j: int):
        o = cam.origin[0]
        w = wp.vec3(1.0)
        start = o
        if wp.static(FIRST):  # a camera ray: entry j is camera ray j
            offset = sample_offset(j % (cam.k * cam.k), cam.k)
            pixel = j / (cam.k * cam.k)
            c = cam.frame
            if wp.static(CAMERA):
                c = camera_of(cam.camera[0], cam.camera[1], cam.camera[2], cam.fovy[0], cam.near, cam.frame.width,
                              cam.frame.height)
            d = camera_ray(c, pixel % c.width, pixel / c.width, offset[0], offset[1])
        else:
            code = entry_parent(rec, j)
            child = (code / 2) * wp.static(BRANCHES) + code % 2
            w = rays.weight[child]
            d = rays.direction[child]
            if wp.static(MOVING):
                o = rays.origin[child]
            if wp.static(ABSORB):
                start = rays.start[code / 2]
        return o, d, w, start

    return replay_ray


@functools.cache
def make_replay_children(MOVING: bool, MIRROR: bool, GLASS: bool):
    """replay_children(s, rec, rays, j, f, hit, d, w): the children entry j's hit spawns, as the forward spawns
    them (a mirror's bounce where follows_mirror, else a dielectric's two rays), left in ``rays`` at
    2 j + branch (with GLASS; j without) for the next level's launch, their origins with MOVING; every one the
    forward could spawn, the record saying which were traced."""
    follows_mirror = make_follows_mirror(True)
    BRANCHES = 2 if GLASS else 1

    @wp.func
    def put(rays: ReplayRays, child: int, ray: Ray, weight: wp.vec3):
        rays.weight[child] = weight
        rays.direction[child] = ray.d
        if wp.static(MOVING):
            rays.origin[child] = ray.o

    @wp.func
    def replay_children(s: SceneData, rec: GradRecord, rays: ReplayRays, j: int, f: int, hit: Surface, d: wp.vec3,
                        w: wp.vec3):
        m = hit.material
        mirrored = False
        if wp.static(MIRROR):
            kr = s.kr[m]
            if follows_mirror(kr, rec, m):
                put(rays, j * wp.static(BRANCHES), mirror_ray(hit, d), wp.cw_mul(w, kr))
                mirrored = True
        if wp.static(GLASS):
            eta = s.ior[m]
            if not mirrored and eta > 0.0:
                ch = dielectric_children(s, f, hit, d, w, eta)
                put(rays, 2 * j, spawn_ray(hit, ch.d_r), ch.w_r)
                put(rays, 2 * j + 1, spawn_ray(hit, ch.d_t), ch.w_t)

    return replay_children


@wp.func
def keep_for_area(hits: ReplayHits, j: int, hit: Surface, k: Coefficients, d: wp.vec3, w: wp.vec3, local: wp.vec3):
    """What replay_area and replay_combine read of entry j's hit."""
    hits.hit[j] = hit
    hits.k[j] = k
    hits.direction[j] = d
    hits.weight[j] = w
    hits.local[j] = local


@functools.cache
def make_replay_level(fx, lights: int, first: bool, moving: bool, camera: bool, absorption: bool):
    """The kernel of one recorded ray level (module docstring): replay_level(s, cam, rec, first_entry, rays, hits,
    colour) over the level's entries from ``first_entry``, adding each one's colour to its camera ray's in
    ``colour``. ``fx``: the recording frame's effects (its smooth normals, textures, vertex colours, light
    model, area lights, mirrors and glass); every Phong term is shaded (a ks of 0 has a derivative). ``first``:
    level 0; ``moving``: the level's hits move (vertices, poses or the camera differentiated; with glass, every
    level but the first: a refracted ray turns with the ior), its children's rays handed on with their origins
    and directions; ``camera``: the camera rays made by the differentiable camera; ``absorption``: Beer's law
    applied. With area lights a hit's local
    colour waits in ``hits`` for replay_area and replay_combine."""
    surface = make_surface(fx.smooth, fx.texture, fx.vertex_color)
    coefficients = make_coefficients(fx.texture, fx.vertex_color)
    light_arrival = make_light_arrival(fx.light_model)
    whitted_term, _ = make_light_terms(True, True)
    replay_ray = make_replay_ray(bool(fx.refraction), first, moving, camera, absorption)
    _, entry_ray, entry_medium = make_entry(bool(fx.refraction))
    replay_children = make_replay_children(moving or fx.refraction, fx.reflection, fx.refraction)
    L, AREA, MOVING, ABSORB = lights, fx.area_lights, moving, absorption
    STARTS = absorption and (fx.reflection or fx.refraction)

    @wp.kernel(module="unique")
    def replay_level(s: SceneData, cam: ReplayCamera, rec: GradRecord, first_entry: int, rays: ReplayRays,
                     hits: ReplayHits, colour: wp.array(dtype=wp.vec3)):
        j = first_entry + wp.tid()
        f = rec.face[j]
        if f == wp.static(NO_RAY):  # no ray reached this entry
            return
        o, d, w, start = replay_ray(cam, rec, rays, j)
        if f == -1:  # ---- met nothing ----
            if wp.static(ABSORB):
                w = absorbed_forever(s, w, entry_medium(rec, s, j))
            wp.atomic_add(colour, entry_ray(rec, j), wp.cw_mul(w, s.background))
        else:
            p0, p1, p2 = triangle(s, f)
            uv = rec.bary[j]
            if wp.static(MOVING):
                uv = barycentrics_on(p0, p1, p2, o, d)
            hit = surface(s, f, uv[0], uv[1], query_normal(p0, p1, p2), d)
            if wp.static(ABSORB):
                w = absorbed(s, w, entry_medium(rec, s, j), start, hit)
            # ---- emitted: an area light's own surface, as recorded ----
            if wp.static(AREA):
                e = rec.emit[j]
                if e >= 0:
                    wp.atomic_add(colour, entry_ray(rec, j), wp.cw_mul(w, s.area.radiance[e]))
            # ---- local shading, the lights seen as recorded ----
            k = coefficients(s, hit)
            local = wp.cw_mul(s.ambient, k.ka)
            seen = rec.visible[j]
            for l in range(wp.static(L)):
                if (seen >> l) & 1 != 0:
                    local = local + whitted_term(light_arrival(s, hit, l), k, s.shininess[hit.material], hit.n, -d)
            if wp.static(AREA):  # the area lights' sample points next (replay_area), then replay_combine
                keep_for_area(hits, j, hit, k, d, w, local)
            else:
                wp.atomic_add(colour, entry_ray(rec, j), wp.cw_mul(w, local))
            # ---- its children ----
            if wp.static(STARTS):
                rays.start[j] = hit.p
            replay_children(s, rec, rays, j, f, hit, d, w)

    return replay_level


area_term = make_light_terms(True, True)[1]


@wp.kernel(module="unique")
def replay_area(s: SceneData, rec: GradRecord, first_entry: int, sample_light: wp.array(dtype=int),
                hits: ReplayHits):
    """The area lights at each hit of a level (one thread per entry t and sample point q: launched over (the
    level's entries, the points)): where the record saw q, area_term of area_arrival added to the entry's
    local colour by wp.atomic_add, differentiable, rather than by a loop over the samples, which Warp would not
    replay backwards (a dynamic one) or could not unroll (over 16). On the CPU the threads run in order, so
    the samples are added as shading.area_light adds them."""
    t, q = wp.tid()
    j = first_entry + t
    if rec.face[j] >= 0:
        if (rec.area_bits[j * rec.words + q / 32] >> (q % 32)) & 1 != 0:
            hit = hits.hit[j]
            term = area_term(area_arrival(s, hit, q), s.area.radiance[sample_light[q]], s.area.dA[q], hits.k[j],
                             s.shininess[hit.material], hit.n, -hits.direction[j])
            wp.atomic_add(hits.local, j, term)


@functools.cache
def make_replay_combine(TREE: bool):
    """replay_combine(rec, first_entry, hits, colour): with area lights, each hit of a level's local colour (the
    area lights' points added) times its weight, added to its camera ray's after its emitted radiance, as the
    tracer adds them."""
    _, entry_ray, _ = make_entry(TREE)

    @wp.kernel(module="unique")
    def replay_combine(rec: GradRecord, first_entry: int, hits: ReplayHits, colour: wp.array(dtype=wp.vec3)):
        j = first_entry + wp.tid()
        if rec.face[j] >= 0:
            wp.atomic_add(colour, entry_ray(rec, j), wp.cw_mul(hits.weight[j], hits.local[j]))

    return replay_combine


@wp.kernel(enable_backward=False)
def sample_mean(rays: wp.array(dtype=wp.vec3), samples: int, image: wp.array(dtype=wp.vec3)):
    """Each pixel's colour from its ``samples`` camera rays' (in sample order) as the trace kernel makes it,
    their sum divided by their number, so the replayed image is the traced one to float32 rounding. Its
    adjoint, linear, is d_image / samples to each ray (image/grad.py gives it to the tape); this kernel
    has none, its loop being dynamic."""
    pixel = wp.tid()
    total = wp.vec3(0.0)
    for sample in range(samples):
        total = total + rays[pixel * samples + sample]
    image[pixel] = total / float(samples)
