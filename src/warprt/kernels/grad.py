"""Gradients of an image through its recorded rays (launched by image/grad.py): the differentiable replay of a
chain of rays (the camera ray, then its mirror rays), and what it shares with glass's tree (grad_tree.py).

The record is the forward's own: the trace kernel's recording variant (kernels/record.py) writes each level's
hit and the Whitted lights and area-light sample points it sees as it traces, with the very tests its shading
makes (shading's make_light_test and make_area_sample_test): what the gradient holds fixed. Glass's tree is
recorded by grad_tree.py's record kernel, which keeps the area lights through make_area_record.
The shading kernel recomputes the local Phong model at those hits from arrays a
wp.Tape differentiates (the material colours and exponents per slot, their textures' texels, the lights'
positions, colours and directions): C = C_amb ka + sum_l vis_l C_l w_l (kd n.L + ks max(0, r.v)^n), w_l a spot's cone times
1 / r^2 for inverse_square (light_factor, shading.light_weight's arithmetic). Its lights loop is unrolled
(wp.static): Warp does not replay a dynamic loop backwards, and a loop longer than max_unroll becomes one.
Area lights' sample points, up to 4096 a light, are no loop: area_replay runs one thread per ray level and
point and adds the point's term (area_sample_term, shading.area_light's) with wp.atomic_add, differentiable;
make_area_combine then sums the levels with the emitted radiance, as the tracer does. The points it reads are
the forward's translated by their light's centre's move (translate_samples, 0 in the replay: a light's
lights.<i>.center gradient). An object's pose (objects.<name>.translation, rotation) moves the points the
replay reads: posed_points, posed_point's Rodrigues formula, ahead of the normals made from them. Vertex
colours multiply ka and kd as the forward's coefficients do, interpolated by vertex_colour at the (moving)
barycentrics from a differentiable per-vertex array. A scene with glass has a ray tree, not a chain of
levels: its record and replay are grad_tree.py's, one launch per level; the hit and local colour both
replays shade are make_replay_surface's and make_replay_local's.
"""

from __future__ import annotations

import functools

from .._warp import wp
from ..geometry import LIGHT_DIRECTIONAL, LIGHT_SPOT, TEXTURE_CLAMP, TEXTURE_MIRROR, TEXTURE_WRAP, SceneData
from ..geometry.bvh import face_vertices
from .camera import camera_of, camera_ray, sample_offset
from .interaction import Surface, hit_point_error, offset_ray_origin, reflect
from .texture import bilinear
from .shading import emitter_met, make_area_sample_test, phong_diffuse, phong_specular

MAX_GRAD_LIGHTS = 16  # Warp's max_unroll: a longer static loop would silently turn dynamic


@wp.func
def spot_cone(cone: wp.vec4, cos_theta: float) -> float:
    """shading.spot_profile with its cone as numbers, differentiable in cos_theta: cone = (cos cutoff,
    cos beam, cutoff, 1 / (cutoff - beam)), LightShape's; 1 within the beam, 0 beyond the cutoff, linear
    in the angle between."""
    if cos_theta <= cone[0]:
        return 0.0
    if cos_theta >= cone[1]:
        return 1.0
    return (cone[2] - wp.acos(cos_theta)) * cone[3]


@wp.func
def light_factor(kind: int, cone: wp.vec4, inverse_square: int, axis: wp.vec3, to_light: wp.vec3,
                 L: wp.vec3) -> float:
    """shading.light_weight over arrays a tape differentiates (the light's axis among them): a spot's
    profile at the angle between -L and its axis, over r^2 for inverse_square; the same arithmetic."""
    w = 1.0
    if kind == wp.static(LIGHT_SPOT):
        w = spot_cone(cone, -wp.dot(L, axis))
    if inverse_square != 0:
        w = w / wp.dot(to_light, to_light)
    return w


TEXTURE_NONE, TEXTURE_IMAGE, TEXTURE_CHECKER = 0, 1, -1  # a colour's texture in the replay's table


@wp.func
def texture_factor(texels: wp.array(dtype=wp.vec3), shape: wp.vec4i, wrap: wp.vec2i, u_map: wp.vec3, v_map: wp.vec3,
                   c0: wp.vec3, c1: wp.vec3, uv: wp.vec3) -> wp.vec3:
    """texture.texel over the replay's table: what a colour is multiplied by at surface coordinates
    uv (as (u, v, 1)): 1 untextured (shape[0] = TEXTURE_NONE), the checker's c0 or c1, or the image's
    bilinear texel (shape = (TEXTURE_IMAGE, offset, width, height), wrap per axis)."""
    if shape[0] == wp.static(TEXTURE_NONE):
        return wp.vec3(1.0)
    q = wp.vec2(wp.dot(u_map, uv), wp.dot(v_map, uv))
    if shape[0] == wp.static(TEXTURE_CHECKER):
        half = (wp.floor(q[0]) + wp.floor(q[1])) * 0.5
        if half == wp.floor(half):
            return c0
        return c1
    return bilinear(texels, shape[1], shape[2], shape[3], wrap[0], wrap[1], q)


@wp.func
def barycentrics_on(p0: wp.vec3, p1: wp.vec3, p2: wp.vec3, o: wp.vec3, d: wp.vec3) -> wp.vec2:
    """Where the ray o + t d meets the plane of the triangle (p0, p1, p2), as (u, v) in Warp's convention (u
    weighs p0, v p1): Moller-Trumbore, differentiable in the points and the ray, without its inside test
    (the face is the recorded one). The replays' hit on a moved face or from a moved ray."""
    e1 = p1 - p0
    e2 = p2 - p0
    pv = wp.cross(d, e2)
    inv = 1.0 / wp.dot(e1, pv)
    tv = o - p0
    b1 = wp.dot(tv, pv) * inv
    b2 = wp.dot(d, wp.cross(tv, e1)) * inv
    return wp.vec2(1.0 - b1 - b2, b1)


@wp.func
def textured(colour: wp.vec3, texels: wp.array(dtype=wp.vec3), tex_shape: wp.array(dtype=wp.vec4i),
             tex_wrap: wp.array(dtype=wp.vec2i), tex_u: wp.array(dtype=wp.vec3), tex_v: wp.array(dtype=wp.vec3),
             tex_c0: wp.array(dtype=wp.vec3), tex_c1: wp.array(dtype=wp.vec3), j: int, uv: wp.vec3) -> wp.vec3:
    """shading.make_coefficients' textured colour: ``colour`` times the texture of the replay's table row j
    (3 m + 0, 1, 2: material slot m's ka, kd, ks) at uv (texture_factor)."""
    return wp.cw_mul(colour, texture_factor(texels, tex_shape[j], tex_wrap[j], tex_u[j], tex_v[j], tex_c0[j],
                                            tex_c1[j], uv))


@functools.cache
def make_whitted_light(light_model: bool):
    """whitted_light(l, ...): Whitted light l's Phong term at a hit it lights (p, normal n, towards the viewer
    v, colours kd and ks, exponent shininess), C_l (kd n.L + ks max(0, r.v)^n): with ``light_model``,
    shading's general model (a directional light's L is -its axis, a spot's cone and 1 / r^2 for
    inverse_square: light_factor); without, the seed's point lights. What the chain's and the tree's
    replays add per light the record saw."""

    @wp.func
    def whitted_light(l: int, light_pos: wp.array(dtype=wp.vec3), light_color: wp.array(dtype=wp.vec3),
                      inverse_square: wp.array(dtype=int), light_kind: wp.array(dtype=int),
                      light_axis: wp.array(dtype=wp.vec3), light_cone: wp.array(dtype=wp.vec4), p: wp.vec3,
                      n: wp.vec3, v: wp.vec3, kd: wp.vec3, ks: wp.vec3, shininess: float) -> wp.vec3:
        C_l = light_color[l]
        if wp.static(light_model):
            to_light = -light_axis[l]
            if light_kind[l] != wp.static(LIGHT_DIRECTIONAL):
                to_light = light_pos[l] - p
            L_dir = wp.normalize(to_light)
            C_l = C_l * light_factor(light_kind[l], light_cone[l], inverse_square[l], light_axis[l], to_light, L_dir)
        else:  # the seed's point lights: no falloff
            to_light = light_pos[l] - p
            L_dir = wp.normalize(to_light)
        n_dot_l = wp.dot(n, L_dir)
        return wp.cw_mul(C_l, kd * n_dot_l + phong_specular(ks, shininess, n, L_dir, v, n_dot_l))

    return whitted_light


@wp.kernel(module="unique")
def camera_rays(camera: wp.array(dtype=wp.vec3), fovy: wp.array(dtype=float), near: float, width: int, height: int,
                k: int, levels: int, dirs: wp.array(dtype=wp.vec3)):
    """Each camera ray's direction (ray pixel * k^2 + sample, as the record numbers them: the pixel's
    stratum centre, camera.sample_offset; written at ray * levels, the record's first level of the ray) from the camera (``camera``: eye and center relative to the frame
    origin, up; ``fovy`` in degrees), differentiable in both: the forward's camera_ray, its basis made in Warp
    (camera_of)."""
    ray = wp.tid()
    pixel = ray / (k * k)
    offset = sample_offset(ray % (k * k), k)
    c = camera_of(camera[0], camera[1], camera[2], fovy[0], near, width, height)
    dirs[ray * levels] = camera_ray(c, pixel % width, pixel / width, offset[0], offset[1])


@functools.cache
def make_area_record(shadows: bool):
    """record_area(s, hit, f, d, j, words, emit, area_bits): what the tree's record keeps of the area lights at
    hit j (``hit`` on face f, met along d): the area light whose emitting side the ray meets (emit[j], -1:
    none; shading.emitter_met, the forward's test) and, as ``words`` int32 bit masks from j words,
    which sample points the hit sees (bit q of word q / 32: shading.make_area_sample_test, the forward
    area_light's own test, lights in order)."""
    area_sample_test = make_area_sample_test(shadows)

    @wp.func(inline=True)
    def record_area(s: SceneData, hit: Surface, f: int, d: wp.vec3, j: int, words: int, emit: wp.array(dtype=int),
                    area_bits: wp.array(dtype=int)):
        emit[j] = emitter_met(s, f, d)
        a = s.area
        for sq in range(a.first[a.num]):
            if area_sample_test(s, hit, sq).lit != 0:
                word = j * words + sq / 32
                area_bits[word] = area_bits[word] | (1 << (sq % 32))

    return record_area


@wp.func
def vertex_colour(colors: wp.array(dtype=wp.vec3), i0: int, i1: int, i2: int, u: float, v: float,
                  w: float) -> wp.vec3:
    """The colour at barycentrics (u, v, w) of the face (i0, i1, i2), as interaction.make_surface
    interpolates it (u on the face's first vertex, v on its second, in that order): differentiable in the
    per-vertex ``colors`` and in the barycentrics, which move with the vertices and the camera."""
    return colors[i0] * u + colors[i1] * v + colors[i2] * w


@functools.cache
def make_replay_surface(smooth: bool, texture: bool, vertex_color: bool, moving: bool):
    """replay_surface(f, uv, o, d, <geometry>, <colours>, <texture table>, colors) -> (p, err, ng, side, n,
    m, ka, kd, ks): the hit of the ray o + t d on recorded face f, made again from the replay's arrays as
    make_surface and shading.make_coefficients make the forward's: at the recorded barycentrics ``uv``, or
    with ``moving`` at those of the moving ray on the face's points (barycentrics_on; ``uv`` unread), the
    point p and with ``moving`` its error bound (hit_point_error; else 0); the geometric normal ng turned
    to face the ray and the side it was turned to (-1: the winding normal's back), the shading normal n on
    that side (with ``smooth``, the interpolated vertex normals where the face's object is smooth); the
    material slot m and its ka, kd, ks at the hit, with ``texture`` times their textures at the
    interpolated uv (textured: the table's rows 3 m + 0, 1, 2), with ``vertex_color`` ka and kd (after
    their textures) times the colour interpolated from ``colors`` (vertex_colour). What the chain's and the
    tree's replays both shade. Plain values, not a struct: each then has one adjoint, summed in the order
    the replay uses it (a struct's field read gets an adjoint of its own, summed apart)."""

    @wp.func(inline=True)
    def replay_surface(f: int, uv: wp.vec2, o: wp.vec3, d: wp.vec3, points: wp.array(dtype=wp.vec3),
                       indices: wp.array(dtype=int), normals: wp.array(dtype=wp.vec3), tri_material: wp.array(dtype=int),
                       tri_smooth: wp.array(dtype=int), ka: wp.array(dtype=wp.vec3), kd: wp.array(dtype=wp.vec3),
                       ks: wp.array(dtype=wp.vec3), uvs: wp.array(dtype=wp.vec2), texels: wp.array(dtype=wp.vec3),
                       tex_shape: wp.array(dtype=wp.vec4i), tex_wrap: wp.array(dtype=wp.vec2i),
                       tex_u: wp.array(dtype=wp.vec3), tex_v: wp.array(dtype=wp.vec3), tex_c0: wp.array(dtype=wp.vec3),
                       tex_c1: wp.array(dtype=wp.vec3), colors: wp.array(dtype=wp.vec3)):
        i0, i1, i2 = face_vertices(indices, f)
        p0 = points[i0]
        p1 = points[i1]
        p2 = points[i2]
        u = uv[0]
        v = uv[1]
        if wp.static(moving):
            moved = barycentrics_on(p0, p1, p2, o, d)
            u = moved[0]
            v = moved[1]
        w = 1.0 - u - v
        p = p0 * u + p1 * v + p2 * w
        ng = wp.normalize(wp.cross(p1 - p0, p2 - p0))
        side = 1.0
        if wp.dot(ng, d) > 0.0:
            side = -1.0
        n = ng * side
        if wp.static(smooth):
            if tri_smooth[f] != 0:
                ns = normals[i0] * u + normals[i1] * v + normals[i2] * w
                if wp.length(ns) > 0.0:
                    n = wp.normalize(ns) * side
        m = tri_material[f]
        ka_m = ka[m]
        kd_m = kd[m]
        ks_m = ks[m]
        if wp.static(texture):  # shading.make_coefficients: the colour times its texture at uv
            t = uvs[i0] * u + uvs[i1] * v + uvs[i2] * w
            uvw = wp.vec3(t[0], t[1], 1.0)
            j = 3 * m
            ka_m = textured(ka_m, texels, tex_shape, tex_wrap, tex_u, tex_v, tex_c0, tex_c1, j, uvw)
            kd_m = textured(kd_m, texels, tex_shape, tex_wrap, tex_u, tex_v, tex_c0, tex_c1, j + 1, uvw)
            ks_m = textured(ks_m, texels, tex_shape, tex_wrap, tex_u, tex_v, tex_c0, tex_c1, j + 2, uvw)
        if wp.static(vertex_color):  # shading.make_coefficients: ka and kd times the vertex colour
            vc = vertex_colour(colors, i0, i1, i2, u, v, w)
            ka_m = wp.cw_mul(ka_m, vc)
            kd_m = wp.cw_mul(kd_m, vc)
        err = wp.vec3(0.0)
        if wp.static(moving):  # what the spawned rays' offset needs (spawn_ray's)
            err = hit_point_error(p0, p1, p2, u, v, w)
        return p, err, ng * side, side, n, m, ka_m, kd_m, ks_m

    return replay_surface


@functools.cache
def make_replay_local(L: int, light_model: bool):
    """replay_local(p, n, d, ka, kd, ks, m, visible, k, ambient, shininess, <lights>): the local colour at a
    replayed hit (point p, shading normal n, material slot m's colours ka, kd, ks there) of the ray along
    d, C_amb ka plus the Phong term of each Whitted light the record saw from it (visible[k L + l]:
    whitted_light), the lights unrolled (wp.static). What the chain's and the tree's replays both add."""

    whitted_light = make_whitted_light(light_model)

    @wp.func(inline=True)
    def replay_local(p: wp.vec3, n: wp.vec3, d: wp.vec3, ka: wp.vec3, kd: wp.vec3, ks: wp.vec3, m: int,
                     visible: wp.array(dtype=int), k: int, ambient: wp.vec3, shininess: wp.array(dtype=float),
                     light_pos: wp.array(dtype=wp.vec3), light_color: wp.array(dtype=wp.vec3),
                     inverse_square: wp.array(dtype=int), light_kind: wp.array(dtype=int),
                     light_axis: wp.array(dtype=wp.vec3), light_cone: wp.array(dtype=wp.vec4)) -> wp.vec3:
        local = wp.cw_mul(ambient, ka)
        for l in range(wp.static(L)):
            if visible[k * wp.static(L) + l] != 0:
                local = local + whitted_light(l, light_pos, light_color, inverse_square, light_kind, light_axis,
                                              light_cone, p, n, -d, kd, ks, shininess[m])
        return local

    return replay_local


@wp.func(inline=True)
def keep_for_area(k: int, p: wp.vec3, n: wp.vec3, kd: wp.vec3, ks: wp.vec3, local: wp.vec3,
                  hit_p: wp.array(dtype=wp.vec3), hit_n: wp.array(dtype=wp.vec3), hit_kd: wp.array(dtype=wp.vec3),
                  hit_ks: wp.array(dtype=wp.vec3), acc: wp.array(dtype=wp.vec3)):
    """What the area lights' replay (area_replay) reads of replayed hit k: its point, normal, kd and ks, and
    in ``acc`` its local colour (replay_local), to which the area lights' samples are added."""
    hit_p[k] = p
    hit_n[k] = n
    hit_kd[k] = kd
    hit_ks[k] = ks
    acc[k] = local


@functools.cache
def make_grad_shade_kernel(L: int, D: int, smooth: bool, moving: bool = False, light_model: bool = False,
                           texture: bool = False, area: bool = False, vertex_color: bool = False):
    """shade(...): each camera ray's colour (one per pixel and sample, as recorded; sample_mean makes
    them the image) from the recorded hits and visibility and the differentiable material and light arrays,
    over the recorded ray levels (D at most), each weighted by the product of the k_r of the mirrors before
    it; the background where a ray met nothing. Each hit is make_replay_surface's and its local colour
    make_replay_local's (``smooth``, ``texture``, ``vertex_color`` and ``light_model`` are theirs). With
    ``moving``, the hit's barycentrics are those of the moving ray (at the first level from ``eye[0]`` along
    ``dirs`` at ray * D, each differentiable: the camera's, camera_rays; then the mirror ray from the
    level's hit point along its direction reflected about the hit's normal, offset off the surface as the
    tracer's spawn_ray does) on the recorded face's ``points``, so that the hit point moves with the
    vertices and the camera (Warp's mesh query gives the points no adjoint), each level's direction written
    to ``ray_dirs`` (the area lights' replay reads it); without, the recorded ones. With ``area``, the
    kernel writes no colour: per ray level it leaves what the area lights' replay needs (keep_for_area, and
    the level's weight), and make_area_combine makes the colour."""

    surface = make_replay_surface(smooth, texture, vertex_color, moving)
    local_colour = make_replay_local(L, light_model)

    @wp.kernel(module="unique")
    def shade(eye: wp.array(dtype=wp.vec3), points: wp.array(dtype=wp.vec3), indices: wp.array(dtype=int), normals: wp.array(dtype=wp.vec3),
              tri_material: wp.array(dtype=int), tri_smooth: wp.array(dtype=int),
              ka: wp.array(dtype=wp.vec3), kd: wp.array(dtype=wp.vec3), ks: wp.array(dtype=wp.vec3),
              shininess: wp.array(dtype=float), kr: wp.array(dtype=wp.vec3), light_pos: wp.array(dtype=wp.vec3),
              light_color: wp.array(dtype=wp.vec3), inverse_square: wp.array(dtype=int),
              light_kind: wp.array(dtype=int), light_axis: wp.array(dtype=wp.vec3), light_cone: wp.array(dtype=wp.vec4),
              uvs: wp.array(dtype=wp.vec2), texels: wp.array(dtype=wp.vec3), tex_shape: wp.array(dtype=wp.vec4i),
              tex_wrap: wp.array(dtype=wp.vec2i), tex_u: wp.array(dtype=wp.vec3), tex_v: wp.array(dtype=wp.vec3),
              tex_c0: wp.array(dtype=wp.vec3), tex_c1: wp.array(dtype=wp.vec3),
              ambient: wp.vec3, background: wp.vec3, face: wp.array(dtype=int), bary: wp.array(dtype=wp.vec2),
              dirs: wp.array(dtype=wp.vec3), visible: wp.array(dtype=int), hit_p: wp.array(dtype=wp.vec3),
              hit_n: wp.array(dtype=wp.vec3), hit_kd: wp.array(dtype=wp.vec3), hit_ks: wp.array(dtype=wp.vec3),
              level_weight: wp.array(dtype=wp.vec3), acc: wp.array(dtype=wp.vec3), ray_dirs: wp.array(dtype=wp.vec3),
              colors: wp.array(dtype=wp.vec3), image: wp.array(dtype=wp.vec3)):
        ray = wp.tid()
        color = wp.vec3(0.0)
        weight = wp.vec3(1.0)
        o = wp.vec3(0.0)  # the moving ray's origin, unread without ``moving``
        if wp.static(moving):  # the moving ray: from the eye along the camera ray, then the mirror rays
            o = eye[0]
            d_next = dirs[ray * wp.static(D)]
        for level in range(wp.static(D)):
            k = ray * wp.static(D) + level
            f = face[k]
            if wp.static(area):
                level_weight[k] = weight  # the product of the k_r before this level
            if f == -1:
                color = color + wp.cw_mul(weight, background)
            if f >= 0:
                d = dirs[k]
                if wp.static(moving):
                    d = d_next
                p, err, ng, side, n, m, ka_m, kd_m, ks_m = surface(f, bary[k], o, d, points, indices, normals,
                                                                  tri_material, tri_smooth, ka, kd, ks, uvs, texels,
                                                                  tex_shape, tex_wrap, tex_u, tex_v, tex_c0, tex_c1,
                                                                  colors)
                local = local_colour(p, n, d, ka_m, kd_m, ks_m, m, visible, k, ambient, shininess, light_pos,
                                     light_color, inverse_square, light_kind, light_axis, light_cone)
                if wp.static(area):
                    keep_for_area(k, p, n, kd_m, ks_m, local, hit_p, hit_n, hit_kd, hit_ks, acc)
                else:
                    color = color + wp.cw_mul(weight, local)
                weight = wp.cw_mul(weight, kr[m])
                if wp.static(moving):  # the mirror ray the tracer spawns here: spawn_ray's, off the surface
                    ray_dirs[k] = d
                    d_next = wp.normalize(reflect(d, n))
                    o = offset_ray_origin(p, err, ng, d_next)
        if wp.static(not area):
            image[ray] = color

    return shade


@wp.func
def area_sample_term(p: wp.vec3, n: wp.vec3, v: wp.vec3, kd: wp.vec3, ks: wp.vec3, shininess: float,
                     point: wp.vec3, normal: wp.vec3, dA: float, L_e: wp.vec3) -> wp.vec3:
    """One area-light sample's light at a hit it lights (shading.area_light's term, in its order): the
    point ``point`` of the emitter (its normal ``normal``, standing for ``dA``) as a point light of
    intensity L_e cos_q dA with inverse-square falloff, L_e (kd max(0, n.L) + ks max(0, r.v)^n)
    cos_q dA / r^2; differentiable in the hit, its colours and exponent, and L_e."""
    to_q = point - p
    r2 = wp.dot(to_q, to_q)
    L = to_q / wp.sqrt(r2)
    n_dot_l = wp.dot(n, L)
    cos_q = -wp.dot(normal, L)
    lit = phong_diffuse(kd, n_dot_l) + phong_specular(ks, shininess, n, L, v, n_dot_l)
    return wp.cw_mul(L_e, lit) * (cos_q * dA / r2)


@wp.kernel(module="unique")
def area_replay(words: int, face: wp.array(dtype=int), dirs: wp.array(dtype=wp.vec3), area_bits: wp.array(dtype=int),
                tri_material: wp.array(dtype=int), shininess: wp.array(dtype=float), hit_p: wp.array(dtype=wp.vec3),
                hit_n: wp.array(dtype=wp.vec3), hit_kd: wp.array(dtype=wp.vec3), hit_ks: wp.array(dtype=wp.vec3),
                points: wp.array(dtype=wp.vec3), normals: wp.array(dtype=wp.vec3), dA: wp.array(dtype=float),
                sample_light: wp.array(dtype=int), radiance: wp.array(dtype=wp.vec3), acc: wp.array(dtype=wp.vec3)):
    """The area lights at each recorded hit, one thread per ray level k and sample point q (launched over
    (rays x levels, samples)): where the record saw q, area_sample_term added to acc[k] (the level's
    local colour, make_grad_shade_kernel's) by wp.atomic_add, differentiable, rather than by a loop over
    the samples, which Warp would not replay backwards (a dynamic one) or could not unroll (over 16).
    On the CPU the threads run in order, so the samples are added as shading.area_light adds them."""
    k, q = wp.tid()
    f = face[k]
    if f >= 0:
        if (area_bits[k * words + q / 32] >> (q % 32)) & 1 != 0:
            term = area_sample_term(hit_p[k], hit_n[k], -dirs[k], hit_kd[k], hit_ks[k], shininess[tri_material[f]],
                                    points[q], normals[q], dA[q], radiance[sample_light[q]])
            wp.atomic_add(acc, k, term)


@wp.kernel(module="unique")
def translate_samples(points0: wp.array(dtype=wp.vec3), sample_light: wp.array(dtype=int),
                      shift: wp.array(dtype=wp.vec3), points: wp.array(dtype=wp.vec3)):
    """The area lights' sample points moved with their lights' centres: points0[q] (the forward's) plus its
    light's shift (c - c0, the centre's move: a shape light's points are its centre plus offsets the
    centre does not change), differentiable in the shift; its normal and dA stay. At a shift of 0 the
    points are the forward's to the bit."""
    q = wp.tid()
    points[q] = points0[q] + shift[sample_light[q]]


POSE_TAYLOR = 1.0e-4  # |w|^2 (radians^2) below which rodrigues_coefficients are their Taylor series


@wp.func
def rodrigues_coefficients(theta2: float) -> wp.vec2:
    """(sin(a) / a, (1 - cos(a)) / a^2) of the angle a = sqrt(theta2), Rodrigues' formula's coefficients:
    below POSE_TAYLOR (a < 0.01) their Taylor series in theta2 to theta2^2 (the next terms below 1e-16), so
    that at a = 0 both and their derivatives are finite (sqrt has none there) and R's Jacobian is the
    cross product's; above, 1 - cos(a) as 2 sin^2(a / 2), without its cancellation."""
    if theta2 < wp.static(POSE_TAYLOR):
        return wp.vec2(1.0 - theta2 / 6.0 + theta2 * theta2 / 120.0, 0.5 - theta2 / 24.0 + theta2 * theta2 / 720.0)
    a = wp.sqrt(theta2)
    half = wp.sin(0.5 * a)
    return wp.vec2(wp.sin(a) / a, 2.0 * half * half / theta2)


@wp.func
def posed_point(v_rest: wp.vec3, c: wp.vec3, t: wp.vec3, w: wp.vec3) -> wp.vec3:
    """R(w) (v_rest - c) + c + t, R(w) the rotation by |w| radians about w / |w| (Rodrigues: R q = q +
    sin(a)/a w x q + (1 - cos(a))/a^2 w x (w x q)), written v_rest + t + (R(w) - I)(v_rest - c) as
    params.posed_vertices writes it: differentiable in t and w, its Jacobian in w at w = 0 the cross product's
    (d/dw at 0 of w x q), finite there (rodrigues_coefficients)."""
    q = v_rest - c
    k = rodrigues_coefficients(wp.dot(w, w))
    wq = wp.cross(w, q)
    return v_rest + t + k[0] * wq + k[1] * wp.cross(w, wq)


@wp.kernel(module="unique")
def posed_points(forward: wp.array(dtype=wp.vec3), rest: wp.array(dtype=wp.vec3), owner: wp.array(dtype=int),
                 centre: wp.array(dtype=wp.vec3), t0: wp.array(dtype=wp.vec3), w0: wp.array(dtype=wp.vec3),
                 t: wp.array(dtype=wp.vec3), w: wp.array(dtype=wp.vec3), points: wp.array(dtype=wp.vec3)):
    """The replay's points from the objects' poses: vertex i of object owner[i] (-1: none of the scene's, an
    area light's own shape, left as it is) is the forward's point plus its pose's change, posed_point of its
    rest point at (t, w) less at the frame's (t0, w0): at the frame's pose the forward's point to the bit (two
    equal values' difference is 0) and differentiable in t and w as posed_point is (the forward poses in
    float64 on the host and rounds; the replay's rest points and centres, relative to the frame origin, are
    float32, which only the derivative reads)."""
    i = wp.tid()
    o = owner[i]
    p = forward[i]
    if o >= 0:
        p = p + (posed_point(rest[i], centre[o], t[o], w[o]) - posed_point(rest[i], centre[o], t0[o], w0[o]))
    points[i] = p


@functools.cache
def make_area_combine(D: int):
    """combine(face, emit, radiance, background, level_weight, acc, image): each camera ray's colour from
    its levels as the tracer sums them, the level's weight times, in turn, the background where it met
    nothing, else the radiance of the area light whose emitting side it met (the recorded emit) and its
    local colour with the area lights (acc); the levels unrolled (wp.static)."""

    @wp.kernel(module="unique")
    def combine(face: wp.array(dtype=int), emit: wp.array(dtype=int), radiance: wp.array(dtype=wp.vec3),
                background: wp.vec3, level_weight: wp.array(dtype=wp.vec3), acc: wp.array(dtype=wp.vec3),
                image: wp.array(dtype=wp.vec3)):
        ray = wp.tid()
        color = wp.vec3(0.0)
        for level in range(wp.static(D)):
            k = ray * wp.static(D) + level
            f = face[k]
            if f == -1:
                color = color + wp.cw_mul(level_weight[k], background)
            if f >= 0:
                e = emit[k]
                if e >= 0:
                    color = color + wp.cw_mul(level_weight[k], radiance[e])
                color = color + wp.cw_mul(level_weight[k], acc[k])
        image[ray] = color

    return combine


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


@wp.func
def corner_angle(a: wp.vec3, b: wp.vec3, c: wp.vec3) -> float:
    """The angle at corner a of the triangle (a, b, c): atan2(|e1 x e2|, e1.e2), e1 = b - a, e2 = c - a, the
    angle normals.face_normals_and_angles takes as arccos of the cosine (the same value, and a derivative
    that stays finite where the cosine nears +-1)."""
    e1 = b - a
    e2 = c - a
    return wp.atan2(wp.length(wp.cross(e1, e2)), wp.dot(e1, e2))


@wp.kernel(module="unique")
def vertex_normal_sums(points: wp.array(dtype=wp.vec3), indices: wp.array(dtype=int), faces: wp.array(dtype=int),
                       position: wp.array(dtype=int), sums: wp.array(dtype=wp.vec3)):
    """normals.vertex_normals' sums, differentiable in ``points``: per face ``faces[tid]`` (the smooth
    objects' whose normals are computed from their triangles), its unit normal (zero where degenerate) times
    each corner's angle (corner_angle) added by wp.atomic_add to the sum of the corner's position
    (``position``: one id per distinct position of an object, normals.position_ids, so that vertices a seam
    splits share one normal)."""
    i0, i1, i2 = face_vertices(indices, faces[wp.tid()])
    p0 = points[i0]
    p1 = points[i1]
    p2 = points[i2]
    fn = wp.normalize(wp.cross(p1 - p0, p2 - p0))
    wp.atomic_add(sums, position[i0], fn * corner_angle(p0, p1, p2))
    wp.atomic_add(sums, position[i1], fn * corner_angle(p1, p2, p0))
    wp.atomic_add(sums, position[i2], fn * corner_angle(p2, p0, p1))


@wp.kernel(module="unique")
def smooth_vertex_normals(sums: wp.array(dtype=wp.vec3), position: wp.array(dtype=int),
                          given: wp.array(dtype=wp.vec3), normals: wp.array(dtype=wp.vec3)):
    """Each vertex's normal as the forward's Geometry has it: where its object's normals are computed from
    its triangles (``position`` >= 0), its position's sum (vertex_normal_sums) normalised, differentiable;
    elsewhere (a file's or a crease's normals, which stay when the vertices move; a flat object's zeros) the
    ``given`` one."""
    v = wp.tid()
    q = position[v]
    if q >= 0:
        normals[v] = wp.normalize(sums[q])
    else:
        normals[v] = given[v]
