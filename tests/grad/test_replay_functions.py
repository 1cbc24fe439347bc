"""The forward's functions the gradient's replay differentiates (kernels/replay.py: one tracer for the image and its
derivative), each through warp.autograd.gradcheck (its adjoints against Warp's own central differences of the
same function) as the replay calls it: the hit record at barycentrics found by the moving ray (barycentrics_on,
then interaction.make_surface with smooth normals, uvs and vertex colours), a mirror's bounce (mirror_ray) and a
dielectric's two children (dielectric_children, spawn_ray), Beer's law over a segment (absorbed); and the
boundary term's own bounce through glass (kernels/glass_edges.py bounce: the ray the crossings' boundary function
follows, in the faces, their normals, the ray and the ior). The light model
and the area lights' terms are checked with their gradients (test_light_gradients.py, test_area_light_gradients.py),
the texture lookup with the texels' (test_texture_gradients.py), the camera rays with the camera's.

The control: the same hit record read through a coordinate rounded to an integer count of millionths (its adjoint
cut where Warp's int cast has none) fails gradcheck, so the check can fail.
"""

from __future__ import annotations

import numpy as np
import warp as wp
import warp.autograd

from warprt.geometry import SceneData
from warprt.kernels import (Surface, absorbed, barycentrics_on, bounce, dielectric_children, make_surface, mirror_ray,
                            spawn_ray)

SURFACE = make_surface(True, True, True)
FACES = [0, 1, 2, 1, 3, 2]  # two triangles of one smooth, textured, coloured object


@wp.func
def scene_of(points: wp.array(dtype=wp.vec3), indices: wp.array(dtype=int), normals: wp.array(dtype=wp.vec3),
             uvs: wp.array(dtype=wp.vec2), colors: wp.array(dtype=wp.vec3), smooth: wp.array(dtype=int),
             transmittance: wp.array(dtype=wp.vec3), absorption: wp.array(dtype=wp.vec3)) -> SceneData:
    """A SceneData of the given tables, one smooth material slot (the rest left empty: not read here)."""
    s = SceneData()
    s.points = points
    s.indices = indices
    s.normals = normals
    s.uvs = uvs
    s.colors = colors
    s.tri_material = smooth  # 1 a face: material slot 1 (the tables below have two rows)
    s.tri_smooth = smooth
    s.transmittance = transmittance
    s.absorption = absorption
    return s


@wp.func
def hit_of(s: SceneData, f: int, o: wp.vec3, d: wp.vec3) -> Surface:
    """The replay's hit of the ray o + t d on face f: barycentrics_on, then the forward's surface."""
    i0 = s.indices[3 * f]
    p0 = s.points[i0]
    p1 = s.points[s.indices[3 * f + 1]]
    p2 = s.points[s.indices[3 * f + 2]]
    uv = barycentrics_on(p0, p1, p2, o, d)
    return SURFACE(s, f, uv[0], uv[1], wp.normalize(wp.cross(p1 - p0, p2 - p0)), d)


@wp.kernel
def _hit(points: wp.array(dtype=wp.vec3), indices: wp.array(dtype=int), normals: wp.array(dtype=wp.vec3),
         uvs: wp.array(dtype=wp.vec2), colors: wp.array(dtype=wp.vec3), smooth: wp.array(dtype=int),
         o: wp.array(dtype=wp.vec3), d: wp.array(dtype=wp.vec3), p: wp.array(dtype=wp.vec3),
         n: wp.array(dtype=wp.vec3), uv: wp.array(dtype=wp.vec2), colour: wp.array(dtype=wp.vec3)):
    i = wp.tid()
    s = scene_of(points, indices, normals, uvs, colors, smooth, colors, colors)
    hit = hit_of(s, i % 2, o[i], wp.normalize(d[i]))
    p[i] = hit.p
    n[i] = hit.n
    uv[i] = hit.uv
    colour[i] = hit.color


@wp.kernel
def _hit_rounded(points: wp.array(dtype=wp.vec3), indices: wp.array(dtype=int), normals: wp.array(dtype=wp.vec3),
                 uvs: wp.array(dtype=wp.vec2), colors: wp.array(dtype=wp.vec3), smooth: wp.array(dtype=int),
                 o: wp.array(dtype=wp.vec3), d: wp.array(dtype=wp.vec3), p: wp.array(dtype=wp.vec3),
                 n: wp.array(dtype=wp.vec3), uv: wp.array(dtype=wp.vec2), colour: wp.array(dtype=wp.vec3)):
    """The control: _hit with the ray's origin read through an int (no adjoint) to a millionth."""
    i = wp.tid()
    s = scene_of(points, indices, normals, uvs, colors, smooth, colors, colors)
    x = o[i]
    held = wp.vec3(float(int(x[0] * 1.0e6)) * 1.0e-6, float(int(x[1] * 1.0e6)) * 1.0e-6, float(int(x[2] * 1.0e6)) * 1.0e-6)
    hit = hit_of(s, i % 2, held, wp.normalize(d[i]))
    p[i] = hit.p
    n[i] = hit.n
    uv[i] = hit.uv
    colour[i] = hit.color


def _vec(rows, dtype=wp.vec3, grad=True):
    return wp.array(np.asarray(rows, np.float32), dtype=dtype, requires_grad=grad)


def _hit_inputs():
    rng = np.random.default_rng(4)
    points = [[-1.0, 0.0, -1.0], [1.0, 0.1, -1.0], [-1.0, -0.1, 1.0], [1.0, 0.0, 1.0]]
    normals = [[0.1, 1.0, 0.0], [0.0, 1.0, 0.2], [-0.1, 1.0, 0.1], [0.0, 1.0, -0.1]]
    normals = np.asarray(normals) / np.linalg.norm(normals, axis=1, keepdims=True)
    o = rng.uniform(-0.3, 0.3, (6, 3)) + [0.0, 2.0, 0.0]
    d = rng.uniform(-0.2, 0.2, (6, 3)) + [0.0, -1.0, 0.0]
    return [_vec(points), wp.array(FACES, dtype=int), _vec(normals), _vec([[0, 0], [1, 0], [0, 1], [1, 1]], wp.vec2),
            _vec(rng.uniform(0.2, 1.0, (4, 3))), wp.array([1, 1], dtype=int), _vec(o), _vec(d)]


def _hit_outputs():
    return [wp.zeros(6, dtype=t, requires_grad=True) for t in (wp.vec3, wp.vec3, wp.vec2, wp.vec3)]


def check(kernel, inputs, outputs, dim) -> bool:
    return warp.autograd.gradcheck(kernel, dim=dim, inputs=inputs, outputs=outputs, eps=1e-3, atol=2e-3, rtol=2e-3,
                                   show_summary=False, raise_exception=False)


def test_the_hit_record_on_a_moving_ray_passes_warps_gradcheck():
    """The hit point, its smooth shading normal, uv and vertex colour, in the vertices, their normals, uvs and
    colours and the ray (the replay's hit where vertices or the camera move)."""
    assert check(_hit, _hit_inputs(), _hit_outputs(), 6)


def test_a_hit_record_whose_adjoint_is_cut_fails_it():
    assert not check(_hit_rounded, _hit_inputs(), _hit_outputs(), 6)


@wp.kernel
def _children(points: wp.array(dtype=wp.vec3), indices: wp.array(dtype=int), normals: wp.array(dtype=wp.vec3),
              uvs: wp.array(dtype=wp.vec2), colors: wp.array(dtype=wp.vec3), smooth: wp.array(dtype=int),
              kt: wp.array(dtype=wp.vec3), sigma: wp.array(dtype=wp.vec3), o: wp.array(dtype=wp.vec3),
              d: wp.array(dtype=wp.vec3), eta: wp.array(dtype=float), weight: wp.array(dtype=wp.vec3),
              origin: wp.array(dtype=wp.vec3), direction: wp.array(dtype=wp.vec3), w: wp.array(dtype=wp.vec3)):
    """Per ray (3 a hit): the mirror's bounce, or a dielectric's reflected and refracted children (their origins
    spawned off the hit, their directions, weights), the weight after Beer over the segment from o."""
    i = wp.tid()
    hit_i = i / 3
    s = scene_of(points, indices, normals, uvs, colors, smooth, kt, sigma)
    ray_d = wp.normalize(d[hit_i])
    hit = hit_of(s, hit_i % 2, o[hit_i], ray_d)
    w_in = absorbed(s, weight[hit_i], 0, o[hit_i], hit)
    ch = dielectric_children(s, hit_i % 2, hit, ray_d, w_in, eta[hit_i])
    if i % 3 == 0:
        r = mirror_ray(hit, ray_d)
        origin[i] = r.o
        direction[i] = r.d
        w[i] = w_in
    if i % 3 == 1:
        origin[i] = spawn_ray(hit, ch.d_r).o
        direction[i] = ch.d_r
        w[i] = ch.w_r
    if i % 3 == 2:
        origin[i] = spawn_ray(hit, ch.d_t).o
        direction[i] = ch.d_t
        w[i] = ch.w_t


def test_the_bounce_the_dielectric_children_and_beer_pass_warps_gradcheck():
    """A mirror's bounce and a dielectric's children through Fresnel and Snell (entering from above, leaving
    from below), with Beer's weight over the segment to the hit, in the vertices, the ray, the ior, k_t and
    sigma (away from the critical angle)."""
    hit_inputs = _hit_inputs()
    rng = np.random.default_rng(5)
    d = rng.uniform(-0.3, 0.3, (6, 3)) + [0.0, -1.0, 0.0]
    o = rng.uniform(-0.3, 0.3, (6, 3)) + [0.0, 2.0, 0.0]
    o[3:, 1], d[3:, 1] = -2.0, 1.0  # from below: leaving the medium
    inputs = hit_inputs[:6] + [_vec([[0.9, 0.8, 0.7]] * 2), _vec([[0.2, 0.1, 0.3]] * 2), _vec(o), _vec(d),
                               wp.array([1.5, 1.33, 1.7, 1.5, 1.4, 1.2], dtype=float, requires_grad=True),
                               _vec(rng.uniform(0.5, 1.0, (6, 3)))]
    outputs = [wp.zeros(18, dtype=wp.vec3, requires_grad=True) for _ in range(3)]
    assert check(_children, inputs, outputs, 18)


@wp.kernel
def _bounced(points: wp.array(dtype=wp.vec3), indices: wp.array(dtype=int), normals: wp.array(dtype=wp.vec3),
             o: wp.array(dtype=wp.vec3), d: wp.array(dtype=wp.vec3), eta: wp.array(dtype=float),
             p: wp.array(dtype=wp.vec3), out: wp.array(dtype=wp.vec3)):
    """Per ray (3 a ray: REFLECTED, TRANSMITTED, MIRRORED, as glass_edges' branches number them) the crossings'
    bounce off face ray % 2 (the smooth pair of _hit_inputs)."""
    i = wp.tid()
    r = i / 3
    f = 3 * (r % 2)
    a, b, c = indices[f], indices[f + 1], indices[f + 2]
    hit, leaves = bounce(o[r], wp.normalize(d[r]), points[a], points[b], points[c], normals[a], normals[b],
                         normals[c], i % 3, eta[r])
    p[i] = hit
    out[i] = leaves


def test_the_glass_edges_bounce_passes_warps_gradcheck():
    """The crossings' bounce (reflected, refracted through Snell, mirrored about the interpolated normal),
    entering from above and leaving from below, in the vertices, their normals, the ray and the ior (the ior's
    adjoint is the boundary term's in materials.<name>.ior: grad_glass_edges._speeds), away from the critical
    angle; the control: the same with the ior's adjoint cut fails it."""
    hit_inputs = _hit_inputs()
    rng = np.random.default_rng(5)
    d = rng.uniform(-0.3, 0.3, (6, 3)) + [0.0, -1.0, 0.0]
    o = rng.uniform(-0.3, 0.3, (6, 3)) + [0.0, 2.0, 0.0]
    o[3:, 1], d[3:, 1] = -2.0, 1.0  # from below: leaving the medium
    inputs = hit_inputs[:3] + [_vec(o), _vec(d), wp.array([1.5, 1.33, 1.7, 1.5, 1.4, 1.2], dtype=float,
                                                          requires_grad=True)]
    outputs = [wp.zeros(18, dtype=wp.vec3, requires_grad=True) for _ in range(2)]
    assert check(_bounced, inputs, outputs, 18)
    assert not check(_bounced_eta_held, inputs, outputs, 18)


@wp.kernel
def _bounced_eta_held(points: wp.array(dtype=wp.vec3), indices: wp.array(dtype=int), normals: wp.array(dtype=wp.vec3),
                      o: wp.array(dtype=wp.vec3), d: wp.array(dtype=wp.vec3), eta: wp.array(dtype=float),
                      p: wp.array(dtype=wp.vec3), out: wp.array(dtype=wp.vec3)):
    """The control: _bounced with the ior read through an int (no adjoint) to a millionth."""
    i = wp.tid()
    r = i / 3
    f = 3 * (r % 2)
    a, b, c = indices[f], indices[f + 1], indices[f + 2]
    held = float(int(eta[r] * 1.0e6)) * 1.0e-6
    hit, leaves = bounce(o[r], wp.normalize(d[r]), points[a], points[b], points[c], normals[a], normals[b],
                         normals[c], i % 3, held)
    p[i] = hit
    out[i] = leaves
