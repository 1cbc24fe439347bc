"""The edges seen through glass's ray tree, for the gradient's boundary term (image/grad_glass_edges.py launches
them): a camera ray's tree signature (each node's face, the lights its shadow rays find blocked and the checker
square it lies in, walked as the forward walks it: make_tree_kernel), and the boundary function of the node where
two signatures part, as a differentiable function of the image point and the parameters through the refractions
and reflections above it, their faces held (make_tree_distances)."""

import functools  # no "from __future__ import annotations": a kernel factory's types are its locals

from .._warp import wp
from ..geometry import CHECKER, LIGHT_DIRECTIONAL, LIGHT_SPOT, SceneData, TextureSlot
from .dielectric import absorbed, dielectric_children, refract
from .interaction import Ray, Surface, make_surface, mirror_ray, reflect, spawn_ray
from .camera import camera_of, image_plane_point
from .clearance import SHADOW_EPSILON
from .mirror import FROM_CAMERA, Mirrors
from .raster import Fragments
from .record import NO_RAY
from .shading import make_area_sample_test, make_coefficients, make_light_arrival, make_light_terms, make_light_test
from .trace import TreeRay, make_first_hit, make_ray_stack

general_light_arrival = make_light_arrival(True)  # where a hard spot is, the general light model is on

REFLECTED, TRANSMITTED, MIRRORED = 0, 1, 2  # how a node's ray leaves its parent's hit
FACE_EDGE, POINT_WEDGE, DIRECTIONAL_WEDGE, SPOT_CONE, CHECKER_LINE = 0, 1, 2, 3, 4  # what parts two signatures: a
# face, a shadow ray's answer, a hard spot's cone, a checker's line
NOT_FOUND = -2  # a detailed walk's blocker of an area light's sample point whose shadow ray is blocked but whose
# nearest hit the query missed (-1: not blocked)
HIDDEN_SEED = 38  # the seed of the sample points' keys (point_key)


@functools.cache
def make_shadow_blocker(LIGHT_MODEL: bool):
    """shadow_blocker(s, hit, L, l): the nearest hit of the shadow ray light_test casts from the hit towards light
    l (L: the unit direction to it; the same origin and direction, so that a ray grazing an edge meets what the
    test's any-hit query met)."""

    @wp.func
    def shadow_blocker(s: SceneData, hit: Surface, L: wp.vec3, l: int) -> wp.MeshQueryRay:
        o = spawn_ray(hit, L).o
        d = wp.normalize(s.light_pos[l] - o)
        if wp.static(LIGHT_MODEL):
            if s.light_shape[l].kind == wp.static(LIGHT_DIRECTIONAL):
                d = L
        return wp.mesh_query_ray(s.mesh, o, d, 1.0e30)

    return shadow_blocker


@wp.func
def detail_columns(s: SceneData) -> int:
    """A detailed walk's blocker columns a node: one per Whitted light, then one per area light sample point."""
    return s.num_lights + s.area.first[s.area.num]


@functools.cache
def make_blocked_lights(fx, DETAIL: bool):
    """blocked_lights(s, hit, k, blocker, blocker_at) -> bits: a bit per Whitted light whose shadow ray from the hit
    is blocked (light_test's, the forward's own test); with DETAIL each such light's nearest blocker's face and
    (u, v) written at node row k, its column the light's (shadow_blocker; detail_columns a row)."""
    light_test = make_light_test(fx.light_model, fx.shadows)
    shadow_blocker = make_shadow_blocker(fx.light_model)

    @wp.func
    def blocked_lights(s: SceneData, hit: Surface, k: int, blocker: wp.array(dtype=int),
                       blocker_at: wp.array(dtype=wp.vec2)) -> int:
        bits = int(0)
        for l in range(s.num_lights):
            t = light_test(s, hit, l)
            if t.shadow_ray != 0 and t.lit == 0:
                bits = bits | (1 << l)
                if wp.static(DETAIL):
                    q = shadow_blocker(s, hit, t.arrival.L, l)
                    blocker[k * detail_columns(s) + l] = wp.where(q.result, q.face, -1)
                    blocker_at[k * detail_columns(s) + l] = wp.vec2(q.u, q.v)
        return bits

    return blocked_lights


@wp.func
def point_key(q: int) -> int:
    """Sample point q's key in a hidden-points sum (a random 32-bit value, the same on every run)."""
    return wp.randi(wp.rand_init(wp.static(HIDDEN_SEED), q))


@functools.cache
def make_hidden_points(fx, DETAIL: bool):
    """hidden_points(s, hit, k, weight, v, blocker, blocker_at, share) -> key: the area lights' sample points whose
    shadow ray from the hit is blocked (make_area_sample_test's, the forward's own test, every ray traced: a light
    proven clear of the scene is unblocked either way), as the exclusive or of their keys (point_key): two sets of
    points part where their keys do, but for a chance of 2^-32. With DETAIL, at node row k and column
    num_lights + q (detail_columns a row), each blocked point's nearest blocker's face and (u, v) (NOT_FOUND where
    the query missed it; -1 stays where unblocked), and each point that faces the hit both ways its share of the
    ray's colour were it seen: ``weight`` (the ray's, as the forward's local shading takes it) times shading's own
    term of it (area_term; ``v`` the direction to the viewer), what its shadow's edge alone jumps by."""
    area_sample_test = make_area_sample_test(True)
    coefficients = make_coefficients(fx.texture, fx.vertex_color)
    _, area_term = make_light_terms(fx.diffuse, fx.specular)

    @wp.func
    def hidden_points(s: SceneData, hit: Surface, k: int, weight: wp.vec3, v: wp.vec3, blocker: wp.array(dtype=int),
                      blocker_at: wp.array(dtype=wp.vec2), share: wp.array(dtype=wp.vec3)) -> int:
        key = int(0)
        a = s.area
        if wp.static(DETAIL):
            coeffs = coefficients(s, hit)
        for e in range(a.num):
            for q in range(a.first[e], a.first[e + 1]):
                t = area_sample_test(s, hit, q, 0)
                blocked = t.shadow_ray != 0 and t.lit == 0
                if blocked:
                    key = key ^ point_key(q)
                if wp.static(DETAIL):
                    c = k * detail_columns(s) + s.num_lights + q
                    if t.shadow_ray != 0:
                        term = area_term(t, a.radiance[e], a.dA[q], coeffs, s.shininess[hit.material], hit.n, v)
                        share[c] = wp.cw_mul(weight, term)
                    if blocked:
                        o = spawn_ray(hit, t.L).o
                        to_q = a.points[q] - o
                        dist = wp.length(to_q)
                        b = wp.mesh_query_ray(s.mesh, o, to_q / dist, dist * wp.static(1.0 - SHADOW_EPSILON))
                        blocker[c] = wp.where(b.result, b.face, wp.static(NOT_FOUND))
                        blocker_at[c] = wp.vec2(b.u, b.v)
        return key

    return hidden_points


@wp.func
def inside_cones(s: SceneData, hit: Surface) -> int:
    """A bit per hard spot (no ramp: its light a step at the cutoff) whose cone holds the hit, as the forward's
    light_arrival decides it (the general light model's)."""
    bits = int(0)
    for l in range(s.num_lights):
        shape = s.light_shape[l]
        if shape.kind == wp.static(LIGHT_SPOT) and shape.inv_ramp == 0.0:
            if general_light_arrival(s, hit, l).reaches != 0:
                bits = bits | (1 << l)
    return bits


@wp.func
def slot_square(slot: TextureSlot, uv: wp.vec2, shift: int) -> int:
    """The checker square uv lies in, as texture.texel maps uv (the same floats: its floors), each floor kept
    mod 32 (neighbouring points' squares differ by fewer), the two floors' 10 bits shifted left by ``shift``;
    0 where the slot is no checker."""
    if slot.image != wp.static(CHECKER):
        return 0
    p = wp.vec3(uv[0], uv[1], 1.0)
    q = wp.vec2(wp.dot(slot.u_map, p), wp.dot(slot.v_map, p))
    return ((int(wp.floor(q[0])) & 31) | ((int(wp.floor(q[1])) & 31) << 5)) << shift


@wp.func
def checker_squares(s: SceneData, hit: Surface) -> int:
    """The checker squares the hit lies in, of its material's ka, kd and ks checkers (slot_square, 10 bits
    each): where two neighbouring points' differ, a checker's line lies between them."""
    m = hit.material
    return slot_square(s.ka_map[m], hit.uv, 0) | slot_square(s.kd_map[m], hit.uv, 10) | slot_square(
        s.ks_map[m], hit.uv, 20)


@functools.cache
def make_node_words(fx, DETAIL: bool, CONES: bool, SQUARES: bool, HIDDEN: bool):
    """node_words(s, hit, k, weight, v, blocked, cone, square, hidden, blocker, blocker_at, share): what a tree node's
    hit writes at its row k beside its face (make_tree_kernel): with shadows its blocked Whitted lights
    (blocked_lights) and with HIDDEN its area lights' blocked sample points (hidden_points; ``weight``, ``v``: its
    ray's), with CONES the hard cones holding it (inside_cones), with SQUARES its checker squares
    (checker_squares); with DETAIL the blockers and shares those write."""
    blocked_lights = make_blocked_lights(fx, DETAIL)
    hidden_points = make_hidden_points(fx, DETAIL)
    SHADOWS = fx.shadows and (fx.diffuse or fx.specular)

    @wp.func
    def node_words(s: SceneData, hit: Surface, k: int, weight: wp.vec3, v: wp.vec3, blocked: wp.array(dtype=int),
                   cone: wp.array(dtype=int), square: wp.array(dtype=int), hidden: wp.array(dtype=int),
                   blocker: wp.array(dtype=int), blocker_at: wp.array(dtype=wp.vec2), share: wp.array(dtype=wp.vec3)):
        if wp.static(SHADOWS):
            blocked[k] = blocked_lights(s, hit, k, blocker, blocker_at)
            if wp.static(HIDDEN):
                hidden[k] = hidden_points(s, hit, k, weight, v, blocker, blocker_at, share)
        if wp.static(CONES):
            cone[k] = inside_cones(s, hit)
        if wp.static(SQUARES):
            square[k] = checker_squares(s, hit)

    return node_words


@functools.cache
def make_tree_kernel(fx, stack: int, nodes: int, DETAIL: bool, CONES: bool = False, SQUARES: bool = False,
                     HIDDEN: bool = False):
    """The kernel that walks camera rays along ``dirs`` through their Whitted tree as trace.make_path walks it
    (nearest hits, Beer's law, a mirror bounce where k_r > 0, else a dielectric's children where they carry weight)
    and writes per point and tree node (``nodes``: node i's reflected or mirror child 2 i + 1, its transmitted child
    2 i + 2) the face hit (NO_RAY: no ray; -1: none) and node_words' (the blocked Whitted lights; with CONES, SQUARES
    and HIDDEN the hard cones, checker squares and blocked sample points' key; the caller sets ``face`` NO_RAY and
    the words 0: a node not reached keeps them); with DETAIL also whether it lies below a dielectric's split, its
    ray (origin, direction), its hit's (u, v, distance) and node_words' blockers and shares (detail_columns a
    node)."""
    first_hit = make_first_hit(False, False, fx.culling)
    surface = make_surface(fx.smooth, fx.texture, fx.vertex_color)
    node_words = make_node_words(fx, DETAIL, CONES, SQUARES, HIDDEN)
    RayRows, waiting, resumed = make_ray_stack(max(stack, 1))
    NodeRows = wp.types.vector(length=max(stack, 1), dtype=int)
    REFLECTION, REFRACTION, ABSORPTION = fx.reflection, fx.refraction, fx.absorption

    @wp.kernel(module="unique", enable_backward=False)
    def tree(s: SceneData, eye: wp.vec3, max_depth: int, frags: Fragments, mir: Mirrors, dirs: wp.array(dtype=wp.vec3),
             face: wp.array(dtype=int), blocked: wp.array(dtype=int), below: wp.array(dtype=int),
             ray: wp.array(dtype=wp.vec3), hit_at: wp.array(dtype=wp.vec3), blocker: wp.array(dtype=int),
             blocker_at: wp.array(dtype=wp.vec2), cone: wp.array(dtype=int), square: wp.array(dtype=int),
             hidden: wp.array(dtype=int), share: wp.array(dtype=wp.vec3)):
        j = wp.tid()
        base = j * nodes
        r = TreeRay(Ray(eye, dirs[j]), wp.vec3(1.0), eye, 0, s.eye_medium, FROM_CAMERA, -1)
        node, under, top = int(0), int(0), int(0)
        rows, node_rows, under_rows = RayRows(), NodeRows(), NodeRows()
        while r.depth < max_depth:
            h = first_hit(s, frags, mir, r, 0, 0, 0, 0, 0)
            k = base + node
            face[k] = h.face
            if wp.static(DETAIL):
                below[k] = under
                ray[2 * k] = r.ray.o
                ray[2 * k + 1] = r.ray.d
            if h.face >= 0:
                hit = surface(s, h.face, h.u, h.v, h.normal, r.ray.d)
                if wp.static(DETAIL):
                    hit_at[k] = wp.vec3(h.u, h.v, wp.length(hit.p - r.ray.o))
                if wp.static(ABSORPTION):
                    r.weight = absorbed(s, r.weight, r.medium, r.start, hit)
                node_words(s, hit, k, r.weight, -r.ray.d, blocked, cone, square, hidden, blocker, blocker_at, share)
                level = r.depth + 1
                if wp.static(REFLECTION):
                    kr = s.kr[hit.material]
                    if level < max_depth and wp.max(kr) > 0.0:
                        r = TreeRay(mirror_ray(hit, r.ray.d), wp.cw_mul(r.weight, kr), hit.p, level, r.medium,
                                    FROM_CAMERA, h.face)
                        node = 2 * node + 1
                        continue
                if wp.static(REFRACTION):
                    eta = s.ior[hit.material]
                    if eta > 0.0 and level < max_depth:
                        ch = dielectric_children(s, h.face, hit, r.ray.d, r.weight, eta)
                        if ch.has_r or ch.has_t:
                            r = TreeRay(spawn_ray(hit, ch.d_r), ch.w_r, hit.p, level, ch.medium_r, FROM_CAMERA, -1)
                            child = 2 * node + 1
                            if ch.has_t:
                                if ch.has_r:
                                    rows[top] = waiting(r)
                                    node_rows[top] = child
                                    under_rows[top] = 1
                                    top += 1
                                r = TreeRay(spawn_ray(hit, ch.d_t), ch.w_t, hit.p, level, ch.medium_t, FROM_CAMERA, -1)
                                child = 2 * node + 2
                            node = child
                            under = 1
                            continue
            if wp.static(REFRACTION):
                if top > 0:
                    top -= 1
                    r = resumed(rows[top])
                    node, under = node_rows[top], under_rows[top]
                    continue
            break

    return tree


@wp.func
def bounce(o: wp.vec3, d: wp.vec3, p0: wp.vec3, p1: wp.vec3, p2: wp.vec3, n0: wp.vec3, n1: wp.vec3, n2: wp.vec3,
           branch: int, eta: float):
    """The hit of the ray (o, d) on the plane of face p0 p1 p2 and the ray it spawns there, as the forward's
    walk spawns it (without its origin's offset): a mirror's bounce about the shading normal (the vertex
    normals n0 n1 n2 interpolated where they are not 0, else the face's), or a dielectric's reflected or
    refracted ray (dielectric_children's normal, Fresnel's side and Snell's eta)."""
    e = wp.cross(p1 - p0, p2 - p0)
    winding = wp.normalize(e)
    p = o + (wp.dot(p0 - o, winding) / wp.dot(d, winding)) * d
    side = wp.where(wp.dot(winding, d) > 0.0, -1.0, 1.0)
    ng = winding * side
    n = ng
    if wp.length(n0) + wp.length(n1) + wp.length(n2) > 0.0:
        ee = wp.dot(e, e)
        u = wp.dot(wp.cross(p1 - p, p2 - p), e) / ee
        v = wp.dot(wp.cross(p2 - p, p0 - p), e) / ee
        ns = n0 * u + n1 * v + n2 * (1.0 - u - v)
        if wp.length(ns) > 0.0:
            n = wp.normalize(ns) * side
    out = wp.normalize(reflect(d, n))
    if branch != wp.static(MIRRORED):
        m = n
        if wp.dot(m, ng) < 0.0:
            m = -m
        if not (wp.dot(d, m) * wp.dot(d, ng) > 0.0):
            m = ng
        out = wp.normalize(reflect(d, m))
        if branch == wp.static(TRANSMITTED):
            eta_rel = wp.where(side > 0.0, eta, 1.0 / eta)  # entering where the ray meets the winding's side
            t, transmits = refract(d, m, eta_rel)
            out = wp.normalize(t)
    return p, out


@functools.cache
def make_tree_distances(LEVELS: int):
    """The kernel of the boundary functions g of crossings (one a thread): the camera ray through the image
    point ``at[c]`` (pixels from the lower-left corner) of the camera ``camera[3 c:3 c + 3]`` and ``fovy[c]``,
    bounced off ``level[c]`` faces in turn (``path``: LEVELS faces' corners a crossing, ``normals`` their vertex
    normals or 0, ``branch`` and ``eta`` how it leaves each: bounce), then per ``kind[c]`` FACE_EDGE's
    det(v0 - o, v1 - o, d) of its ray (o, d) and the edge ``edge[2 c:2 c + 2]``, or a shadow wedge's N . (y - v0),
    N = (v0 - L) x (v1 - v0) (POINT_WEDGE, L = ``light[c]``) or L x (v1 - v0) (DIRECTIONAL_WEDGE, L the direction of
    travel), or a hard spot's cone's unit(y - L) . v0 - ``cos_cutoff[c]`` (SPOT_CONE: L its position, v0 its axis),
    or a checker's line's a u + b v + c - k (CHECKER_LINE: v0 its value at the face's three corners, y's barycentric
    weights on them), y the ray's hit on the face path[LEVELS c + level]. Differentiable in the path, the edge, the
    light, the eta of each refraction (a dielectric's ior), the camera and the image point; each crossing reads
    copies of its own."""

    @wp.kernel(module="unique")
    def tree_distances(path: wp.array(dtype=wp.vec3), edge: wp.array(dtype=wp.vec3), light: wp.array(dtype=wp.vec3),
                       normals: wp.array(dtype=wp.vec3), branch: wp.array(dtype=int), eta: wp.array(dtype=float),
                       level: wp.array(dtype=int), kind: wp.array(dtype=int), cos_cutoff: wp.array(dtype=float),
                       camera: wp.array(dtype=wp.vec3),
                       fovy: wp.array(dtype=float), near: float, width: int, height: int, at: wp.array(dtype=wp.vec2),
                       distance: wp.array(dtype=float)):
        c = wp.tid()
        cam = camera_of(camera[3 * c], camera[3 * c + 1], camera[3 * c + 2], fovy[c], near, width, height)
        d = wp.normalize(image_plane_point(cam, at[c][0] / float(width), at[c][1] / float(height)))
        o = camera[3 * c]
        for k in range(wp.static(LEVELS - 1)):
            if k < level[c]:
                f = 3 * (LEVELS * c + k)
                o, d = bounce(o, d, path[f], path[f + 1], path[f + 2], normals[f], normals[f + 1], normals[f + 2],
                              branch[LEVELS * c + k], eta[LEVELS * c + k])
        v0, v1 = edge[2 * c], edge[2 * c + 1]
        g = wp.dot(wp.cross(v0 - o, v1 - o), d)
        if kind[c] != wp.static(FACE_EDGE):
            f = 3 * (LEVELS * c + level[c])
            e = wp.cross(path[f + 1] - path[f], path[f + 2] - path[f])
            y = o + (wp.dot(path[f] - o, e) / wp.dot(d, e)) * d
            if kind[c] == wp.static(SPOT_CONE):
                g = wp.dot(wp.normalize(y - light[c]), v0) - cos_cutoff[c]
            elif kind[c] == wp.static(CHECKER_LINE):
                ee = wp.dot(e, e)
                u = wp.dot(wp.cross(path[f + 1] - y, path[f + 2] - y), e) / ee
                v = wp.dot(wp.cross(path[f + 2] - y, path[f] - y), e) / ee
                g = v0[0] * u + v0[1] * v + v0[2] * (1.0 - u - v)
            else:
                n = wp.cross(light[c], v1 - v0)
                if kind[c] == wp.static(POINT_WEDGE):
                    n = wp.cross(v0 - light[c], v1 - v0)
                g = wp.dot(n, y - v0)
        distance[c] = g

    return tree_distances
