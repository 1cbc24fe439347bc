"""Gradients of an image through Whitted's full ray tree, glass included (image/grad_record.py's tree record,
image/grad.py's replay): a record kernel and a differentiable replay kernel, each launched once per ray level.

Warp does not replay a dynamic loop backwards, nor a stack pushed and popped in place, so the tree is not
walked as the forward walks it (trace.py's depth-first loop and ray stack). The record follows the forward's
tree level by level instead: per level a flat list of rays (the camera rays, then each level's children in
their parents' order, the reflected child before the transmitted one), each ray's nearest hit, the lights it
sees and its children found with the forward's own functions (make_surface, absorbed, make_light_test,
dielectric_children, spawn_ray), so every ray is the forward's to the bit; the host compacts each level's
children into the next level's list (image/grad_record.py). The replay kernel, one launch per level, reads the
level's rays (origin, direction, weight, where its segment began) from arrays the previous level's launch
wrote, and writes its children's into new arrays, never in place: a wp.Tape replays each launch backwards.
Each node recomputes its hit on the recorded face from the moving ray (a differentiable Moller-Trumbore
test, as make_grad_shade_kernel's moving hits), Beer's law over the segment in the ray's medium, the local
Phong terms with the recorded visibility, and its children: a mirror's (k_r), or a dielectric's reflected
(F) and refracted ((1 - F) k_t) ray through Fresnel (fresnel_dielectric), Snell (refract) and the spawn
offset, as dielectric_children does it. Held fixed: each ray's face, each shadow ray's visibility, the
tree's structure (which children exist, total internal reflection), each ray's medium. The tree is the
forward's, and where a transmittance of 0 keeps the forward from tracing a refracted ray (it would carry
nothing), that ray too, with weight 0: its radiance is the derivative in that transmittance.
"""

from __future__ import annotations

import functools

from .._warp import wp
from ..geometry import SceneData
from .camera import CameraData, camera_ray, sample_offset
from .dielectric import absorbed, beer, beer_forever, dielectric_children, fresnel_dielectric, refract
from .grad import keep_for_area, make_area_record, make_replay_local, make_replay_surface
from .interaction import Surface, make_surface, offset_ray_origin, reflect, spawn_ray
from .shading import make_light_test
from .trace import culled, past


CHILD_NONE, CHILD_MIRROR, CHILD_DIELECTRIC = 0, 1, 2  # what a recorded ray spawns


@wp.kernel(module="unique", enable_backward=False)
def tree_camera_rays(s: SceneData, c: CameraData, k: int, first: int, orig: wp.array(dtype=wp.vec3),
                     dirs: wp.array(dtype=wp.vec3), weight: wp.array(dtype=wp.vec3), start: wp.array(dtype=wp.vec3),
                     medium: wp.array(dtype=int)):
    """The tree's first level: each camera ray (ray pixel * k^2 + sample, as the trace kernel's record numbers
    them) as the trace kernel makes it: from the eye, weight 1, in the eye's medium."""
    ray = first + wp.tid()
    pixel = ray / (k * k)
    offset = sample_offset(ray % (k * k), k)
    orig[ray] = c.eye
    dirs[ray] = camera_ray(c, pixel % c.width, pixel / c.width, offset[0], offset[1])
    weight[ray] = wp.vec3(1.0)
    start[ray] = c.eye
    medium[ray] = s.eye_medium


@wp.func(inline=True)
def put_child(o: wp.array(dtype=wp.vec3), d: wp.array(dtype=wp.vec3), w: wp.array(dtype=wp.vec3),
              x: wp.array(dtype=wp.vec3), med: wp.array(dtype=int), i: int, hit: Surface, direction: wp.vec3,
              weight: wp.vec3, reach: wp.vec3, medium: int):
    """A child of ray i recorded as the forward spawns it off ``hit`` along ``direction`` (spawn_ray): its
    origin, direction, weight, reach and medium at i of the child kind's arrays."""
    ray = spawn_ray(hit, direction)
    o[i] = ray.o
    d[i] = ray.d
    w[i] = weight
    x[i] = reach
    med[i] = medium


@functools.cache
def make_tree_record_kernel(L: int, smooth: bool, shadows: bool, cull: bool, light_model: bool, reflection: bool,
                            absorption: bool, area: bool = False):
    """record(s, max_depth, level, first, <the level's rays>, <what it records>, <its children>): per ray of
    a level's list (from ``first``), its nearest hit's face (-1: none), whether it sees each light
    (shading.make_light_test, the forward's own test) and what it spawns (kind: CHILD_NONE,
    CHILD_MIRROR while k_r > 0 and the level allows, else CHILD_DIELECTRIC where ior > 0, as the forward's
    path decides), with each child (has: reflected, transmitted) as the forward makes it: origin, direction,
    weight and medium; and the children a transmittance of 0 keeps the forward from tracing (its refracted
    ray, weight 0, and what that one spawns: ``reach``, each ray's weight with such transmittances taken as
    1, decides), so that the derivative in that transmittance is not lost; likewise the mirror rays of the
    materials ``mirror_anyway`` flags (render(grad=[their reflectivity]): a k_r of 0's derivative). ``reflection``, ``absorption``: the forward's effects of those names. With ``area``, also
    the area light whose emitting side the ray meets (emit, -1: none) and which area-light sample points the
    hit sees (``words`` int32 bit masks a ray), as the trace kernel's record (kernels/record.py) holds them."""
    surface = make_surface(smooth)
    light_test = make_light_test(light_model, shadows)
    record_area = make_area_record(shadows)

    @wp.kernel(module="unique", enable_backward=False)
    def record(s: SceneData, max_depth: int, level: int, first: int, orig: wp.array(dtype=wp.vec3),
               dirs: wp.array(dtype=wp.vec3), weight: wp.array(dtype=wp.vec3), start: wp.array(dtype=wp.vec3),
               medium: wp.array(dtype=int), face: wp.array(dtype=int), visible: wp.array(dtype=int), kind: wp.array(dtype=int), has: wp.array(dtype=wp.vec2i),
               hit_p: wp.array(dtype=wp.vec3), o_r: wp.array(dtype=wp.vec3), d_r: wp.array(dtype=wp.vec3),
               w_r: wp.array(dtype=wp.vec3), med_r: wp.array(dtype=int), o_t: wp.array(dtype=wp.vec3),
               d_t: wp.array(dtype=wp.vec3), w_t: wp.array(dtype=wp.vec3), med_t: wp.array(dtype=int),
               emit: wp.array(dtype=int), area_bits: wp.array(dtype=int), words: int, reach: wp.array(dtype=wp.vec3),
               x_r: wp.array(dtype=wp.vec3), x_t: wp.array(dtype=wp.vec3), mirror_anyway: wp.array(dtype=int)):
        i = first + wp.tid()
        d = dirs[i]
        q = wp.mesh_query_ray(s.mesh, orig[i], d, 1.0e30)
        if wp.static(cull):
            while q.result and culled(s, q.face, d):
                q = wp.mesh_query_ray(s.mesh, past(s, q.face, q.u, q.v, d), d, 1.0e30)
        face[i] = -1
        kind[i] = wp.static(CHILD_NONE)
        has[i] = wp.vec2i(0, 0)
        if q.result:
            face[i] = q.face  # its barycentrics the replay finds again from its moving ray
            hit = surface(s, q.face, q.u, q.v, q.normal, d)
            hit_p[i] = hit.p
            w = weight[i]
            x = reach[i]
            if wp.static(absorption):
                w = absorbed(s, w, medium[i], start[i], hit)
                x = absorbed(s, x, medium[i], start[i], hit)
            for l in range(wp.static(L)):
                visible[i * wp.static(L) + l] = light_test(s, hit, l).lit
            if wp.static(area):
                record_area(s, hit, q.face, d, i, words, emit, area_bits)
            children = level + 1
            mirrored = False
            if wp.static(reflection):
                kr = s.kr[hit.material]
                anyway = mirror_anyway[hit.material] != 0  # render(grad=[its reflectivity]), k_r 0 or not
                if children < max_depth and (wp.max(kr) > 0.0 or anyway):  # a mirror's ray stays in its medium
                    reach_m = wp.cw_mul(x, kr)
                    if anyway and wp.max(kr) <= 0.0:  # the reach as if k_r were 1: its subtree is recorded too
                        reach_m = x
                    put_child(o_r, d_r, w_r, x_r, med_r, i, hit, wp.normalize(reflect(d, hit.n)), wp.cw_mul(w, kr),
                              reach_m, medium[i])
                    kind[i] = wp.static(CHILD_MIRROR)
                    has[i] = wp.vec2i(1, 0)
                    mirrored = True
            eta = s.ior[hit.material]
            if not mirrored and eta > 0.0 and children < max_depth:
                ch = dielectric_children(s, q.face, hit, d, w, eta)
                # The reach: a transmittance of 0 (every channel) lets the forward's refracted ray carry
                # nothing, so it is not traced, but the derivative in that transmittance is its radiance:
                # the record follows it (and its own children) as if the transmittance were 1; its weight,
                # the forward's, is 0, so the image is unchanged.
                F = dielectric_children(s, q.face, hit, d, wp.vec3(1.0), eta).w_r[0]
                kt = s.transmittance[hit.material]
                if wp.max(kt) <= 0.0:
                    kt = wp.vec3(1.0)
                reach_r = x * F
                reach_t = wp.cw_mul(x, kt) * (1.0 - F)
                has_r = ch.has_r or wp.max(reach_r) > 0.0
                has_t = ch.has_t or (F < 1.0 and wp.max(reach_t) > 0.0)
                if has_r or has_t:
                    kind[i] = wp.static(CHILD_DIELECTRIC)
                    has[i] = wp.vec2i(wp.where(has_r, 1, 0), wp.where(has_t, 1, 0))
                    if has_r:
                        put_child(o_r, d_r, w_r, x_r, med_r, i, hit, ch.d_r, ch.w_r, reach_r, ch.medium_r)
                    if has_t:
                        put_child(o_t, d_t, w_t, x_t, med_t, i, hit, ch.d_t, ch.w_t, reach_t, ch.medium_t)

    return record


@wp.func
def dielectric_normal(d: wp.vec3, ng: wp.vec3, n: wp.vec3) -> wp.vec3:
    """The normal Fresnel and Snell use at a dielectric hit (dielectric_children's): the shading normal n
    turned to the side of ng (the geometric normal facing the ray), or ng where n is tilted past the ray."""
    m = n
    if wp.dot(m, ng) < 0.0:
        m = -m
    if not (wp.dot(d, m) * wp.dot(d, ng) > 0.0):
        m = ng
    return m


@functools.cache
def make_tree_replay_kernel(L: int, smooth: bool, light_model: bool, texture: bool, first: bool, absorption: bool,
                            area: bool = False, vertex_color: bool = False):
    """replay(...): one level of the recorded tree, differentiable. Per ray of the level's list: its ray
    (with ``first``, the camera ray from ``eye[0]`` along ``dirs``, weight 1; else the origin, direction,
    weight and segment start its parent's launch wrote), its hit recomputed on the recorded face from that
    ray (make_replay_surface, moving), with ``absorption`` Beer's law over the segment in the recorded
    medium (beer; beer_forever for a ray that meets nothing), its colour (the background, or
    make_replay_local's) times its weight added to its camera ray's (wp.atomic_add), and its recorded
    children written at their places in the next level's arrays (children): a mirror's (k_r), a
    dielectric's reflected (weight F) and refracted ((1 - F) k_t) ray, Fresnel's F at the ior
    (fresnel_dielectric), the direction by Snell (refract), origins offset as spawn_ray offsets them. With
    ``area``, a ray that hits adds no colour here: it leaves what the area lights' replay needs
    (keep_for_area, its direction and its weight), and tree_area_combine adds it to its camera ray's."""

    surface = make_replay_surface(smooth, texture, vertex_color, True)
    local_colour = make_replay_local(L, light_model)

    @wp.func(inline=True)
    def children(p: wp.vec3, err: wp.vec3, ng: wp.vec3, side: float, n: wp.vec3, m: int, d: wp.vec3, w: wp.vec3,
                 kind: int, c: wp.vec2i, kr: wp.array(dtype=wp.vec3), ior: wp.array(dtype=float),
                 kt: wp.array(dtype=wp.vec3), o_next: wp.array(dtype=wp.vec3), d_next: wp.array(dtype=wp.vec3),
                 w_next: wp.array(dtype=wp.vec3), start_next: wp.array(dtype=wp.vec3)):
        """The recorded children of a ray along d with weight w at its replayed hit (replay_surface's p, err,
        ng, side, n, m), at their places c in the next level's arrays."""
        if kind == wp.static(CHILD_MIRROR):
            d_m = wp.normalize(reflect(d, n))
            o_next[c[0]] = offset_ray_origin(p, err, ng, d_m)
            d_next[c[0]] = d_m
            w_next[c[0]] = wp.cw_mul(w, kr[m])
            start_next[c[0]] = p
        if kind == wp.static(CHILD_DIELECTRIC):
            mn = dielectric_normal(d, ng, n)
            cos_i = -wp.dot(d, mn)
            eta = ior[m]
            eta_rel = eta
            cos_f = cos_i
            if side < 0.0:  # leaving: the ray meets the winding normal's back
                eta_rel = 1.0 / eta
                cos_f = -cos_i
            F = fresnel_dielectric(cos_f, eta)
            if c[0] >= 0:
                d_r = wp.normalize(reflect(d, mn))
                o_next[c[0]] = offset_ray_origin(p, err, ng, d_r)
                d_next[c[0]] = d_r
                w_next[c[0]] = w * F
                start_next[c[0]] = p
            if c[1] >= 0:
                tr, transmits = refract(d, mn, eta_rel)
                d_t = wp.normalize(tr)
                o_next[c[1]] = offset_ray_origin(p, err, ng, d_t)
                d_next[c[1]] = d_t
                w_next[c[1]] = wp.cw_mul(w, kt[m]) * (1.0 - F)
                start_next[c[1]] = p

    @wp.kernel(module="unique")
    def replay(eye: wp.array(dtype=wp.vec3), points: wp.array(dtype=wp.vec3), indices: wp.array(dtype=int),
               normals: wp.array(dtype=wp.vec3), tri_material: wp.array(dtype=int), tri_smooth: wp.array(dtype=int),
               ka: wp.array(dtype=wp.vec3), kd: wp.array(dtype=wp.vec3), ks: wp.array(dtype=wp.vec3),
               shininess: wp.array(dtype=float), kr: wp.array(dtype=wp.vec3), ior: wp.array(dtype=float),
               kt: wp.array(dtype=wp.vec3), sigma: wp.array(dtype=wp.vec3), light_pos: wp.array(dtype=wp.vec3),
               light_color: wp.array(dtype=wp.vec3), inverse_square: wp.array(dtype=int),
               light_kind: wp.array(dtype=int), light_axis: wp.array(dtype=wp.vec3), light_cone: wp.array(dtype=wp.vec4),
               uvs: wp.array(dtype=wp.vec2), texels: wp.array(dtype=wp.vec3), tex_shape: wp.array(dtype=wp.vec4i),
               tex_wrap: wp.array(dtype=wp.vec2i), tex_u: wp.array(dtype=wp.vec3), tex_v: wp.array(dtype=wp.vec3),
               tex_c0: wp.array(dtype=wp.vec3), tex_c1: wp.array(dtype=wp.vec3), ambient: wp.vec3, background: wp.vec3,
               face: wp.array(dtype=int), visible: wp.array(dtype=int), medium: wp.array(dtype=int),
               ray_of: wp.array(dtype=int), kind: wp.array(dtype=int), child: wp.array(dtype=wp.vec2i),
               orig: wp.array(dtype=wp.vec3), dirs: wp.array(dtype=wp.vec3), weight: wp.array(dtype=wp.vec3),
               start: wp.array(dtype=wp.vec3), rays: wp.array(dtype=wp.vec3), o_next: wp.array(dtype=wp.vec3),
               d_next: wp.array(dtype=wp.vec3), w_next: wp.array(dtype=wp.vec3), start_next: wp.array(dtype=wp.vec3),
               hit_p: wp.array(dtype=wp.vec3), hit_n: wp.array(dtype=wp.vec3), hit_kd: wp.array(dtype=wp.vec3),
               hit_ks: wp.array(dtype=wp.vec3), level_weight: wp.array(dtype=wp.vec3), acc: wp.array(dtype=wp.vec3),
               ray_dirs: wp.array(dtype=wp.vec3), colors: wp.array(dtype=wp.vec3)):
        i = wp.tid()
        f = face[i]
        d = dirs[i]
        o = eye[0]
        w = wp.vec3(1.0)
        st = eye[0]
        if wp.static(not first):
            o = orig[i]
            w = weight[i]
            st = start[i]
        med = medium[i]
        if f == -1:
            if wp.static(absorption):
                if med >= 0:  # it leaves the scene inside the medium
                    w = beer_forever(w, sigma[med])
            wp.atomic_add(rays, ray_of[i], wp.cw_mul(w, background))
        if f >= 0:
            p, err, ng, side, n, m, ka_m, kd_m, ks_m = surface(f, wp.vec2(0.0, 0.0), o, d, points, indices, normals,
                                                              tri_material, tri_smooth, ka, kd, ks, uvs, texels,
                                                              tex_shape, tex_wrap, tex_u, tex_v, tex_c0, tex_c1,
                                                              colors)  # on the face, from the moving ray
            if wp.static(absorption):
                if med >= 0:  # the segment from where the ray began, not its offset origin
                    w = beer(w, sigma[med], wp.length(p - st))
            local = local_colour(p, n, d, ka_m, kd_m, ks_m, m, visible, i, ambient, shininess, light_pos, light_color,
                                 inverse_square, light_kind, light_axis, light_cone)
            if wp.static(area):
                keep_for_area(i, p, n, kd_m, ks_m, local, hit_p, hit_n, hit_kd, hit_ks, acc)
                level_weight[i] = w
                ray_dirs[i] = d
            else:
                wp.atomic_add(rays, ray_of[i], wp.cw_mul(w, local))
            children(p, err, ng, side, n, m, d, w, kind[i], child[i], kr, ior, kt, o_next, d_next, w_next, start_next)

    return replay


@wp.kernel(module="unique")
def tree_area_combine(face: wp.array(dtype=int), emit: wp.array(dtype=int), radiance: wp.array(dtype=wp.vec3),
                      ray_of: wp.array(dtype=int), level_weight: wp.array(dtype=wp.vec3), acc: wp.array(dtype=wp.vec3),
                      rays: wp.array(dtype=wp.vec3)):
    """With area lights, each hit of a tree level's colour added to its camera ray's: its weight times the
    radiance of the area light whose emitting side it met (the recorded emit) and its local colour with the
    area lights' samples (acc), as the tracer adds them (make_area_combine's, for a level's list)."""
    i = wp.tid()
    if face[i] >= 0:
        c = acc[i]
        e = emit[i]
        if e >= 0:
            c = radiance[e] + c
        wp.atomic_add(rays, ray_of[i], wp.cw_mul(level_weight[i], c))
