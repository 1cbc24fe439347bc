"""Whitted's full ray tree on Mitsuba 3: at each level, one wide Mitsuba evaluation over a flat batch
of rays (origin, direction, RGB weight, pixel, sample, medium), each ray's children spawned with
their weights, both branches and no random choice (Mitsuba's own dielectric picks one).

Per level: the nearest hit (Embree); Beer's law exp(-sigma t) over the segment, in the ray's medium;
the local Phong terms and shadows (the integrator's own local()) or the background; then the children:
a mirror's reflected ray (weight k_r) or, at a dielectric, the reflected (F) and the refracted
((1 - F) k_t, none past the critical angle) ray, with mi.fresnel, mi.reflect, mi.refract and
si.spawn_ray. Children at level max_depth are not traced: their weight is the TreeResult's
``truncated``. The eye's medium is found with Mitsuba's intersection too (eye_medium_row).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


@dataclass
class TreeResult:
    image: np.ndarray  # (H, W, 3) float32 linear RGB: the mean over the pixel's k*k samples
    truncated: np.ndarray  # (H, W, 3) float64: the weight of the children max_depth cut off (sample mean)
    escaped: np.ndarray  # (H, W, 3) float64: the weight (after absorption) of the rays that hit nothing
    rays_per_level: list  # rays traced at each level
    records: list | None = None  # per level, for the recorded pixels: each ray's numpy values


def _vec(v) -> np.ndarray:
    """A Dr.Jit 3-vector as an (N, 3) numpy array (same dtype, same bits)."""
    return np.ascontiguousarray(np.array(v).T)


def _dr3(tp, a: np.ndarray):
    """An (N, 3) numpy array as a Dr.Jit 3-vector type (Point3f, Vector3f, Color3f)."""
    return tp(np.ascontiguousarray(np.asarray(a, np.float32).T))


def primary_rays(ms, camera, spp: int):
    """The rays mi.render traces with this sensor: film position (x + sx, row + sy) / (W, H), sx, sy at
    the k*k stratum centres (the non-jittered stratified sampler), box filter (a sample feeds only its
    own pixel, weight 1). Numpy origins, directions, maxt, and each ray's pixel (row * W + x) and sample."""
    mi = ms.mi
    k = math.isqrt(spp)
    W, H = int(camera.width), int(camera.height)
    pixel = np.repeat(np.arange(W * H), k * k)
    sample = np.tile(np.arange(k * k), W * H)
    f32 = np.float32
    sx = ((sample % k).astype(f32) + f32(0.5)) / f32(k)
    sy = ((sample // k).astype(f32) + f32(0.5)) / f32(k)
    # As Mitsuba computes it: pos = pixel + sample (float32), adjusted = fmadd(pos, rcp(film size), 0).
    ux = ((pixel % W).astype(f32) + sx) * (f32(1.0) / f32(W))
    uy = ((pixel // W).astype(f32) + sy) * (f32(1.0) / f32(H))
    ray, _ = ms.sensor(camera, spp).sample_ray(mi.Float(0.0), mi.Float(0.5), mi.Point2f(ux, uy), mi.Point2f(0.5, 0.5))
    return _vec(ray.o), _vec(ray.d), np.array(ray.maxt), pixel, sample


# Directions from the eye along which its medium is read: irrational slopes, so that a ray is
# unlikely to pass exactly through a mesh's edge; the majority of the three decides.
_PROBES = ((0.5377, 0.8031, 0.2566), (-0.6701, 0.3119, -0.6734), (0.1297, -0.4418, 0.8877))


def eye_medium_row(ms, eye, max_crossings: int = 4096) -> int:
    """The table row of the dielectric shape that holds the eye (0: air), counted along rays from the
    eye with Mitsuba's intersection: a closed surface holding the eye is left once more than entered."""
    mi, dr = ms.mi, ms.dr
    t = ms.integrator.tables
    if not t.dielectric_rows:
        return 0
    votes = []
    for direction in _PROBES:
        d = np.asarray(direction, np.float64)
        ray = mi.Ray3f(mi.Point3f(*map(float, eye)), mi.Vector3f(*map(float, d / np.linalg.norm(d))))
        balance: dict[int, int] = {}
        for _ in range(max_crossings):
            si = ms.mi_scene.ray_intersect(ray)
            if not bool(dr.all(si.is_valid())):
                break
            row = int(dr.reinterpret_array(mi.UInt32, si.shape)[0])
            if row in t.dielectric_rows:
                leaving = float(dr.dot(si.n, ray.d)[0]) > 0.0
                balance[row] = balance.get(row, 0) + (1 if leaving else -1)
            ray = si.spawn_ray(ray.d)
        inside = [r for r, b in balance.items() if b > 0]
        if len(inside) > 1:
            raise ValueError("the eye is inside more than one dielectric object")
        votes.append(inside[0] if inside else 0)
    return max(set(votes), key=votes.count)


def render_tree(ms, switches, camera=None, record=None) -> TreeResult:
    """The ray tree of ``ms`` (a MitsubaScene) under ``switches`` (reference.Switches), level by level.
    ``record``: (x, row) pixels whose rays are kept level by level, for explaining a pixel."""
    mi, dr = ms.mi, ms.dr
    t = ms.integrator.tables
    if not t.jit:
        raise NotImplementedError("the ray tree needs a JIT variant of Mitsuba (llvm_ad_rgb)")
    k = math.isqrt(switches.spp)
    if k * k != switches.spp:
        raise ValueError(f"spp must be a square (k*k stratified samples), got {switches.spp}")
    camera = camera or ms.scene.camera
    integ = ms.integrator
    integ.switches = switches
    W, H = int(camera.width), int(camera.height)
    P = W * H
    o, d, maxt, pixel, sample = primary_rays(ms, camera, switches.spp)
    start = o.copy()  # where each ray's segment begins: its parent's hit point before the offset (the eye)
    n = len(o)
    w = np.ones((n, 3), np.float32)
    med = np.full(n, eye_medium_row(ms, camera.eye) if switches.absorption else 0, np.uint32)
    code = np.ones(n, np.uint64)  # the path: a leading 1, then a bit per level, 0 reflected, 1 refracted
    acc, trunc, esc = np.zeros((P, 3)), np.zeros((P, 3)), np.zeros((P, 3))
    want = None if record is None else np.array(sorted({row * W + x for x, row in record}), np.int64)
    records = [] if want is not None else None
    counts = []
    flags = mi.RayFlags.Minimal | mi.RayFlags.ShadingFrame
    if t.attributes or t.own_textures:  # textures read the mesh's uv, not the barycentrics
        flags = flags | mi.RayFlags.UV
    zero = mi.Color3f(0.0)

    def add(target, index, values):
        for ch in range(3):
            target[:, ch] += np.bincount(index, weights=values[:, ch], minlength=P)

    for level in range(switches.max_depth):
        n = len(o)
        counts.append(n)
        if n == 0:
            break
        ray = mi.Ray3f(_dr3(mi.Point3f, o), _dr3(mi.Vector3f, d))
        ray.maxt = mi.Float(np.asarray(maxt, np.float32))
        si = integ.intersect(ms.mi_scene, ray, flags, level == 0, mi.Bool(True))  # past culled back faces
        hit = si.is_valid()
        row = dr.reinterpret_array(mi.UInt32, si.shape)  # the hit shape's table row (0: a miss)
        wgt = _dr3(mi.Color3f, w)
        medium = mi.UInt32(med)
        if switches.absorption:
            # Beer's law over the segment just travelled, measured from the parent's hit point (the
            # offset origin would shorten each segment by Mitsuba's offset); a miss travels for ever.
            sig = dr.gather(mi.Color3f, t.sigma, medium)
            dist = dr.select(hit, dr.norm(si.p - _dr3(mi.Point3f, start)), dr.inf)
            wgt = wgt * dr.select(sig > 0.0, dr.exp(-sig * dist), 1.0)
        # The local terms as the integrator computes them: normals turned to face the ray by the geometric side.
        side = dr.select(dr.dot(si.n, ray.d) > 0.0, -1.0, 1.0)
        sh = dr.select(dr.isfinite(si.sh_frame.n.x), si.sh_frame.n, si.n)
        nrm = sh * side
        mat = integ.material(si, hit)
        local = integ.local(ms.mi_scene, si, mat, nrm, -ray.d, hit)
        contrib = dr.select(hit, wgt * local, wgt * t.background)
        kr = mat[3] if switches.reflection else zero
        eta = dr.gather(mi.Float, t.eta, row, hit)
        glass = hit & (eta > 0.0) & mi.Bool(switches.refraction)
        mirror = hit & ~glass & (dr.max(kr) > 0.0)
        # A dielectric: m = the shading normal turned to the winding normal's side, or si.n where the
        # ray meets m from the other side than si.n. cos_w > 0 (d.n_g < 0) is entering: mi.fresnel
        # takes eta from outside, 1/eta from inside.
        m = dr.mulsign(sh, dr.dot(sh, si.n))
        cos_w = dr.dot(-ray.d, m)
        cos_g = dr.dot(-ray.d, si.n)
        fallback = glass & ~(cos_w * cos_g > 0.0)
        m = dr.select(fallback, si.n, m)
        cos_w = dr.select(fallback, cos_g, cos_w)
        F, cos_t, _, eta_ti = mi.fresnel(cos_w, dr.select(glass, eta, 1.0))
        kt = dr.gather(mi.Color3f, t.kt, row, hit)
        dir_r = dr.select(glass, dr.normalize(mi.reflect(-ray.d, m)),
                          dr.normalize(ray.d - 2.0 * dr.dot(ray.d, nrm) * nrm))  # a mirror: the integrator's rule
        dir_t = dr.normalize(mi.refract(-ray.d, m, cos_t, eta_ti))
        w_r = wgt * dr.select(glass, mi.Color3f(F), kr)
        w_t = wgt * (1.0 - F) * kt
        has_r = (glass | mirror) & (dr.max(w_r) > 0.0)
        has_t = glass & (F < 1.0) & (dr.max(w_t) > 0.0)
        ray_r = si.spawn_ray(dir_r)  # Mitsuba's offset: (1 + max|p|) RayEpsilon along si.n, to dir's side
        ray_t = si.spawn_ray(dir_t)
        # A dielectric's child is inside it where it leaves against the winding normal; a mirror's
        # keeps its parent's medium.
        med_r = dr.select(glass, dr.select(dr.dot(dir_r, si.n) < 0.0, row, 0), medium)
        med_t = dr.select(dr.dot(dir_t, si.n) < 0.0, row, 0)
        dr.eval(contrib, wgt, hit, ray_r.o, ray_r.d, ray_t.o, ray_t.d, w_r, w_t, has_r, has_t, med_r, med_t,
                F, cos_w, fallback, si.t, row)
        contrib_np, hit_np, p_np, wgt_np = _vec(contrib), np.array(hit), _vec(si.p), _vec(wgt)
        add(acc, pixel, contrib_np.astype(np.float64))
        add(esc, pixel[~hit_np], wgt_np[~hit_np].astype(np.float64))
        hr, ht = np.array(has_r), np.array(has_t)
        wr, wt = _vec(w_r), _vec(w_t)
        if records is not None:
            sel = np.isin(pixel, want)
            records.append({"level": level, "pixel": pixel[sel], "sample": sample[sel], "code": code[sel],
                            "o": o[sel], "d": d[sel], "w": w[sel], "medium": med[sel], "hit": hit_np[sel],
                            "t": np.array(si.t)[sel], "row": np.array(row)[sel], "contrib": contrib_np[sel],
                            "F": np.array(F)[sel], "has_r": hr[sel], "has_t": ht[sel]})
        if level + 1 >= switches.max_depth:
            add(trunc, pixel[hr], wr[hr].astype(np.float64))
            add(trunc, pixel[ht], wt[ht].astype(np.float64))
            break
        start = np.concatenate([p_np[hr], p_np[ht]])
        o = np.concatenate([_vec(ray_r.o)[hr], _vec(ray_t.o)[ht]])
        d = np.concatenate([_vec(ray_r.d)[hr], _vec(ray_t.d)[ht]])
        maxt = np.full(len(o), np.finfo(np.float32).max, np.float32)
        w = np.concatenate([wr[hr], wt[ht]])
        med = np.concatenate([np.array(med_r)[hr], np.array(med_t)[ht]]).astype(np.uint32)
        code = np.concatenate([code[hr] * np.uint64(2), code[ht] * np.uint64(2) + np.uint64(1)])
        pixel = np.concatenate([pixel[hr], pixel[ht]])
        sample = np.concatenate([sample[hr], sample[ht]])
    s = float(k * k)
    shape = (H, W, 3)
    return TreeResult((acc / s).reshape(shape).astype(np.float32), (trunc / s).reshape(shape),
                      (esc / s).reshape(shape), counts, records)


def path_name(code: int) -> str:
    """A path code as 'P' (the primary ray) and one letter per level after it: R reflected, T refracted."""
    return "P" + "".join("T" if c == "1" else "R" for c in bin(int(code))[3:])
