"""Brute-force Whitted tracers in float64 on the shared ray-triangle test and Phong model: a
per-pixel tracer with decision margins (the accuracy suite's tie-breaker), and a one-level one.

Whitted tests every triangle with Moller-Trumbore in float64 (no BVH, no float32), so where it
agrees with a renderer the renderer's decisions are the exact ones for the offsets it chose. Textures are
sampled in float64 (bilinear, repeat, written here from the convention, not from either renderer),
uvs and vertex colours interpolated with its own barycentrics. With glass it walks the whole ray tree
(the rules of reference/ray_tree.py, written again in numpy: Fresnel and Snell from optics.py) and keeps
every ray of it as a Branch, so a pixel where the renderers differ can be traced to the branch that differs.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .camera import pinhole, ray_directions
from .geometry import face_normals, nearest_triangle, ray_triangle, vertex_normals, winding_number
from .optics import fresnel
from .shading import TERMS, light_direction, light_source, phong

# Mitsuba (include/mitsuba/render/interaction.h, offset_p and spawn_ray_to): (1 + max|p|) RayEpsilon
# along the geometric normal, RayEpsilon = 1500 * 2^-24; shadow rays stop ShadowEpsilon short.
MITSUBA_RAY_EPSILON = 1500.0 * 2.0**-24
MITSUBA_SHADOW_EPSILON = 10.0 * MITSUBA_RAY_EPSILON
# warprt's offset is a float32 error bound (src/warprt/kernels/interaction.py) that its authors tune; the oracle
# does not copy it. It tries offsets of (1 + max|p|) times each of these instead, from next to
# nothing up to Mitsuba's: a renderer whose value one of them reproduces decided as the exact model
# does for an origin that close to the surface.
OFFSET_SWEEP = (2.0**-20, 2.0**-23, 2.0**-17, 2.0**-26, 2.0**-14, 2.0**-34)  # likeliest first


@dataclass
class Branch:
    """One ray of a sample's tree: where it went and what it brought back."""

    sample: int
    path: int  # a leading 1, then a bit per level after the primary: 0 reflected, 1 refracted (path_name)
    obj: int  # the object hit, -1 for a miss
    t: float
    weight: np.ndarray  # on arrival, after absorption
    contribution: np.ndarray  # weight * (local terms, or the background)
    margin: float  # the smallest decision margin of this ray: its query, n.L, side and normal choices


@dataclass
class PixelTrace:
    color: np.ndarray  # linear RGB, the average over the pixel's k*k samples
    margin: float  # smallest decision margin met on any ray of any sample (see Whitted._query)
    truncated: np.ndarray = field(default_factory=lambda: np.zeros(3))  # weight of the rays max_depth cut off
    branches: list = field(default_factory=list)

    def explain(self, limit: int = 6) -> str:
        """The pixel's largest contributions, ray by ray: path, object hit, distance, value, margin."""
        from reference import path_name

        top = sorted(self.branches, key=lambda b: -float(np.max(b.contribution)))[:limit]
        return "; ".join(f"sample {b.sample} {path_name(b.path)} hits object {b.obj} at t {b.t:.6g} giving "
                         f"{np.round(b.contribution, 4)} (margin {b.margin:.1e})" for b in top)


class Whitted:
    """The scene's triangles in float64 world space and the Whitted model of reference.Switches:
    I = local Phong + k_r I(reflected ray), or F I(reflected) + (1 - F) k_t I(refracted) at a
    dielectric, up to max_depth ray levels, shadows by shadow rays."""

    def __init__(self, scene, switches):
        self.scene, self.sw = scene, switches
        names = list(scene.materials)
        verts, faces, mat, smooth, normals, uvs, colors, base = [], [], [], [], [], [], [], 0
        for obj in scene.objects:
            verts.append(obj.vertices)
            faces.append(obj.faces + base)
            mat += [names.index(obj.material)] * len(obj.faces)
            use_smooth = obj.smooth and switches.smooth
            smooth += [use_smooth] * len(obj.faces)
            given = getattr(obj, "normals", None)  # the file's own, or split at a crease, as the scene gives them
            normals.append((given if given is not None else vertex_normals(obj.vertices, obj.faces)) if use_smooth
                           else np.zeros_like(obj.vertices))
            uvs.append(obj.uv if getattr(obj, "uv", None) is not None else np.zeros((len(obj.vertices), 2)))
            colors.append(obj.colors if getattr(obj, "colors", None) is not None and switches.vertex_color
                          else np.ones((len(obj.vertices), 3)))
            base += len(obj.vertices)
        self.V = np.concatenate(verts)
        self.F = np.concatenate(faces)
        self.N = np.concatenate(normals)
        self.UV = np.concatenate(uvs).astype(np.float64)
        self.C = np.concatenate(colors).astype(np.float64)
        self.mat = np.asarray(mat)
        self.smooth = np.asarray(smooth)
        self.p0, self.p1, self.p2 = (self.V[self.F[:, k]] for k in range(3))
        # Bounding spheres, a little enlarged: a ray that misses one is far from every decision
        # about its triangle, so only the others are tested (a large mesh stays quick).
        self.centre = (self.p0 + self.p1 + self.p2) / 3.0
        radius = np.max([np.linalg.norm(q - self.centre, axis=1) for q in (self.p0, self.p1, self.p2)], axis=0)
        self.radius2 = (radius * 1.01 + 1e-9) ** 2
        self.n_hat = face_normals(np.stack([self.p0, self.p1, self.p2], 1))
        # Altitudes over the edges opposite p0, p1, p2: barycentric b_k times h_k is the distance
        # to that edge's line, so decision margins can be measured in world units.
        area2 = np.linalg.norm(np.cross(self.p1 - self.p0, self.p2 - self.p0), axis=1)
        with np.errstate(divide="ignore", invalid="ignore"):
            self.h = np.stack([area2 / np.linalg.norm(self.p2 - self.p1, axis=1),
                               area2 / np.linalg.norm(self.p2 - self.p0, axis=1),
                               area2 / np.linalg.norm(self.p1 - self.p0, axis=1)], 1)
        self.materials = [scene.materials[n] for n in names]
        # Per face: a single-sided material, whose back faces camera, reflected and refracted rays pass through.
        self.single = np.array([not getattr(m, "double_sided", True) for m in self.materials], bool)[self.mat]
        self.obj = np.concatenate([np.full(len(o.faces), i) for i, o in enumerate(scene.objects)])
        # Per object: the dielectric's eta (0: opaque), k_t and sigma as the switches let them act.
        glass = [scene.materials[o.material] for o in scene.objects]
        self.eta = np.array([m.ior if (m.dielectric and switches.refraction) else 0.0 for m in glass])
        self.kt = np.array([m.transmittance for m in glass], np.float64).reshape(-1, 3)
        self.sigma = np.array([m.absorption if switches.absorption else (0.0, 0.0, 0.0) for m in glass],
                              np.float64).reshape(-1, 3)
        # The medium the camera rays start in: the dielectric object whose inside holds the eye.
        self.eye_object = next((i for i, (o, m) in enumerate(zip(scene.objects, glass)) if m.dielectric
                                and winding_number(o.vertices, o.faces, scene.camera.eye) > 0.5), -1)

    def _query(self, o, d, tmax, cull: bool = False):
        """Nearest hit (face, t, b1, b2) or None (with ``cull``, not counting single-sided faces seen from
        behind, as glTF culls them), and the query's decision margin, relative to the
        coordinates' magnitude (1 + max|p|), as float32 rounding is: how far the ray passes from an
        edge of any triangle whose plane it crosses before the hit, and the gap to a second
        triangle hit at (nearly) the same distance."""
        oc = self.centre - o
        tc = oc @ d
        near = np.nonzero(np.einsum("ij,ij->i", oc, oc) - tc * tc <= self.radius2)[0]
        if len(near) == 0:
            return None, math.inf
        q = ray_triangle(o, d, self.p0[near], self.p1[near], self.p2[near])
        b1, b2, t, h = q.u, q.v, q.t, self.h[near]
        cos = np.abs(self.n_hat[near] @ d)
        with np.errstate(invalid="ignore"):
            # Signed distance in the plane to the nearest edge line (exact inside, and outside next to
            # an edge), times |n.d|: how far the ray must move sideways to cross that edge, which
            # for a grazing ray is much less than the distance in the plane.
            edge_distance = np.minimum(np.minimum((1.0 - b1 - b2) * h[:, 0], b1 * h[:, 1]), b2 * h[:, 2]) * cos
            scale = 1.0 + np.abs(o + t[:, None] * d).max(axis=1)
        in_range = np.isfinite(t) & (t > 0.0) & (t < tmax)
        hit = in_range & (q.margin >= 0.0)
        if cull:
            hit &= ~(self.single[near] & (self.n_hat[near] @ d > 0.0))
        tt = np.where(hit, t, np.inf)
        f = int(np.argmin(tt))
        t_hit = tt[f]
        before = in_range & (t <= (t_hit * (1 + 1e-6) if np.isfinite(t_hit) else tmax))
        margin = float(np.nanmin(np.abs(edge_distance[before]) / scale[before])) if before.any() else math.inf
        if np.isfinite(t_hit):
            others = hit & (np.arange(len(t)) != f)
            if others.any():
                margin = min(margin, float((tt[others].min() - t_hit) / scale[f]))
            return (int(near[f]), t_hit, b1[f], b2[f]), margin
        return None, margin

    @staticmethod
    def _offset(offset, p, ng, w):
        """The origin of a ray leaving the surface point p in direction w: pushed along the
        geometric normal ng, to the side w leaves to, by (1 + max|p|) times the relative offset
        (Mitsuba's RayEpsilon for offset="mitsuba")."""
        rel = MITSUBA_RAY_EPSILON if offset == "mitsuba" else float(offset)
        mag = (1.0 + float(np.abs(p).max())) * rel
        return p + ng * (mag if ng @ w > 0 else -mag)

    def _local(self, offset, p, ng, n, d, mat, uv, vertex_color):
        """C_amb ka + sum_l vis_l C_l (kd n.L + ks (r.v)^n) at p, with ka, kd, ks at the hit, and the
        margin of its decisions."""
        sw, scene = self.sw, self.scene
        terms = [t for t, on in zip(TERMS, (sw.ambient, sw.diffuse, sw.specular)) if on]
        (ka, kd, ks), margin = self._coefficients(mat, uv, vertex_color)
        visible = None
        if sw.diffuse or sw.specular:
            visible = np.zeros(len(scene.lights), bool)
            for i, light in enumerate(scene.lights):
                L, n_dot_l = light_direction(p, n, light)
                margin = min(margin, abs(float(n_dot_l)))
                if not n_dot_l > 0.0:
                    continue
                visible[i] = True
                if sw.shadows:
                    so = self._offset(offset, p, ng, L)
                    if light_source(light)[0] is None:  # a directional light: the ray leaves the scene
                        direction, tmax = L, math.inf
                    else:
                        to_light = light_source(light)[0] - so
                        dist = float(np.linalg.norm(to_light))
                        direction = to_light / dist
                        tmax = dist * (1.0 - MITSUBA_SHADOW_EPSILON) if offset == "mitsuba" else dist
                    blocker, m = self._query(so, direction, tmax)
                    margin = min(margin, m)
                    visible[i] = blocker is None
        local = phong(p, n, -d, scene.lights, {"ka": ka, "kd": kd, "ks": ks, "shininess": mat.shininess},
                      scene.render.ambient, visible, terms)
        return local, margin

    def _children(self, d, w, medium, f, ng_raw, side, n, margin):
        """The rays a hit on face f spawns: [(direction, weight, medium, path bit)] and the margin.
        A mirror's reflected ray keeps the medium; at a dielectric the reflected (F) and refracted
        ((1 - F) k_t) rays, each inside the glass where it leaves against the winding normal."""
        obj = int(self.obj[f])
        eta = self.eta[obj]
        if eta <= 0.0:
            kr = np.asarray(self.materials[self.mat[f]].reflectivity, np.float64)
            if not self.sw.reflection or kr.max() <= 0.0:
                return [], margin
            r = d - 2.0 * (d @ n) * n
            return [(r / np.linalg.norm(r), w * kr, medium, 0)], margin
        sh = n * side  # the shading normal as the winding orients it
        m_n = sh * (1.0 if sh @ ng_raw >= 0 else -1.0)  # ...turned to the winding normal's side
        cos_w, cos_g = -float(d @ m_n), -float(d @ ng_raw)
        margin = min(margin, abs(cos_g))  # which side the ray comes from
        if self.smooth[f]:
            margin = min(margin, abs(cos_w))  # where the shading normal gives way to the geometric one
        if not cos_w * cos_g > 0.0:
            m_n, cos_w = ng_raw, cos_g
        entering = cos_w > 0.0
        e_i, e_t = (1.0, eta) if entering else (eta, 1.0)
        nn = m_n if entering else -m_n  # the normal on the incident side
        ci = abs(cos_w)
        F = float(fresnel(ci, e_i, e_t))
        r = d + 2.0 * ci * nn
        kids = [(r / np.linalg.norm(r), w * F)]
        k2 = 1.0 - (e_i / e_t) ** 2 * (1.0 - ci * ci)
        if F < 1.0 and k2 > 0.0:
            t = (e_i / e_t) * d + ((e_i / e_t) * ci - math.sqrt(k2)) * nn
            kids.append((t / np.linalg.norm(t), w * (1.0 - F) * self.kt[obj]))
        out = []
        for bit, (kd, kw) in enumerate(kids):  # bit 0: reflected, 1: refracted
            margin = min(margin, abs(float(kd @ ng_raw)))  # the child's medium
            out.append((kd, kw, obj if kd @ ng_raw < 0.0 else -1, bit))
        return out, margin

    def _sample(self, offset, o, d, sample: int = 0, out: PixelTrace | None = None):
        """The tree of one camera ray, level by level as the reference traces it (the order does not
        change the sums): its colour and smallest decision margin; rays and truncated weight go to out."""
        out = out if out is not None else PixelTrace(np.zeros(3), math.inf)
        sw, scene = self.sw, self.scene
        background = np.asarray(scene.render.background, np.float64)
        color, margin = np.zeros(3), math.inf
        level_rays = [(o, d, np.ones(3), self.eye_object, 1, o)]  # ..., medium, path, segment start (not offset)
        for depth in range(sw.max_depth):
            next_rays = []
            for o, d, w, medium, path, start in level_rays:
                hit, ray_margin = self._query(o, d, math.inf, cull=True)
                sigma = self.sigma[medium] if medium >= 0 else np.zeros(3)
                if hit is None:
                    w = np.where(sigma > 0.0, 0.0, w)  # exp(-sigma * infinity)
                    color = color + w * background
                    out.branches.append(Branch(sample, path, -1, math.inf, w, w * background, ray_margin))
                    margin = min(margin, ray_margin)
                    continue
                f, t, b1, b2 = hit
                b = (1.0 - b1 - b2, b1, b2)
                p = self.p0[f] * b[0] + self.p1[f] * b[1] + self.p2[f] * b[2]
                w = w * np.exp(-sigma * np.linalg.norm(p - start))  # from the parent's hit point
                ng_raw = self.n_hat[f]
                side = -1.0 if ng_raw @ d > 0 else 1.0  # two-sided: turn the normals towards the ray
                ng = ng_raw * side
                n = ng
                if self.smooth[f]:
                    ns = sum(self.N[self.F[f, k]] * b[k] for k in range(3))
                    n = ns / np.linalg.norm(ns) * side
                uv = sum(self.UV[self.F[f, k]] * b[k] for k in range(3))
                vertex_color = sum(self.C[self.F[f, k]] * b[k] for k in range(3))
                local, m = self._local(offset, p, ng, n, d, self.materials[self.mat[f]], uv, vertex_color)
                ray_margin = min(ray_margin, m)
                color = color + w * local
                kids, ray_margin = self._children(d, w, medium, f, ng_raw, side, n, ray_margin)
                kids = [kid for kid in kids if kid[1].max() > 0.0]
                out.branches.append(Branch(sample, path, int(self.obj[f]), t, w, w * local, ray_margin))
                margin = min(margin, ray_margin)
                if depth + 1 >= sw.max_depth:
                    for _, kw, _, _ in kids:
                        out.truncated = out.truncated + kw
                    continue
                for kd, kw, km, bit in kids:
                    next_rays.append((self._offset(offset, p, ng, kd), kd, kw, km, path * 2 + bit, p))
            level_rays = next_rays
            if not level_rays:
                break
        return color, margin

    def _coefficients(self, mat, uv, color):
        """(ka, kd, ks) at a hit of texture coordinates uv and vertex colour color, and the decision
        margin of any checker there (how far the mapped uv is from a check's edge, relative to it)."""
        out, margin = [], math.inf
        for key in ("ka", "kd", "ks"):
            k = np.asarray(getattr(mat, key), np.float64)
            t = getattr(mat, f"{key}_texture", None)
            if t is not None and self.sw.texture:
                value, m = texture_value(t, uv)
                k, margin = k * value, min(margin, m)
            out.append(k * color if key != "ks" else k)
        return out, margin

    def pixel(self, x: int, row: int, offset="mitsuba") -> PixelTrace:
        """Pixel (x, row), row 0 at the top, averaged over k*k samples at the stratum centres, with
        secondary rays offset as Mitsuba does (offset="mitsuba") or by (1 + max|p|) * offset."""
        k = math.isqrt(self.sw.spp)
        cam = pinhole(self.scene.camera)
        out = PixelTrace(np.zeros(3), math.inf)
        total, margin = np.zeros(3), math.inf
        for j in range(k):
            for i in range(k):
                d = ray_directions(cam, x, row, (i + 0.5) / k, (j + 0.5) / k)
                c, m = self._sample(offset, cam.eye.copy(), d / np.linalg.norm(d), j * k + i, out)
                total += c
                margin = min(margin, m)
        out.color, out.margin = total / (k * k), margin
        out.truncated = out.truncated / (k * k)
        return out


def texture_value(t, uv) -> tuple[np.ndarray, float]:
    """A warprt Texture at surface coordinates uv, in float64: the uv map, then repeat wrap and bilinear
    filtering between the texel centres ((i + 0.5) / W, (j + 0.5) / H), image row 0 at v = 0; or the
    checker, c0 where floor(u') + floor(v') is even. Returns the value and the checker's decision margin
    (the distance of u' or v' to the nearest integer, relative to 1 + |uv'|; inf for images)."""
    a = t.uv_transform
    q = np.array([a[0] * uv[0] + a[1] * uv[1] + a[2], a[3] * uv[0] + a[4] * uv[1] + a[5]])
    if t.checker is not None:
        parity = int(np.floor(q[0]) + np.floor(q[1])) % 2
        edge = float(np.min(np.abs(q - np.round(q))))
        return np.asarray(t.checker[parity], np.float64), edge / (1.0 + float(np.abs(q).max()))
    image = np.asarray(t.image, np.float64)
    h, w = image.shape[:2]
    x, y = np.mod(q[0], 1.0) * w - 0.5, np.mod(q[1], 1.0) * h - 0.5
    x0, y0 = int(np.floor(x)), int(np.floor(y))
    fx, fy = x - x0, y - y0
    c = lambda i, j: image[j % h, i % w]
    return ((c(x0, y0) * (1 - fx) + c(x0 + 1, y0) * fx) * (1 - fy)
            + (c(x0, y0 + 1) * (1 - fx) + c(x0 + 1, y0 + 1) * fx) * fy), math.inf


def shade_triangles(o, d, tris, face_mats, materials, lights, c_amb, background):
    """The seed's model on a flat triangle scene, one ray level with shadows, vectorized over rays
    (o, d: (..., 3)): each ray's colour is the Phong value of its nearest face (normal turned to face
    the ray: two-sided), with a light counted where a shadow ray from just off the hit point reaches
    it unblocked. Returns colour, face (-1: the background), edge margin (see nearest_triangle)."""
    t, face, margin = nearest_triangle(o, d, tris)
    p = o + np.where(np.isfinite(t), t, 0.0)[..., None] * d
    out = np.broadcast_to(np.asarray(background, float), p.shape).copy()
    n = face_normals(tris)[face]
    n *= -np.sign(np.sum(n * d, -1))[..., None]
    visible = np.ones(p.shape[:-1] + (len(lights),), bool)
    for i, light in enumerate(lights):
        L, _ = light_direction(p, n, light)
        position, _ = light_source(light)
        dist = np.linalg.norm(position - p, axis=-1) if position is not None else np.full(p.shape[:-1], np.inf)
        start = p + n * 1e-9 * (1.0 + np.abs(p).max(-1, keepdims=True))
        tl, _, _ = nearest_triangle(start, L, tris)
        visible[..., i] = tl >= dist
    for m, mat in enumerate(materials):
        here = (np.asarray(face_mats)[face] == m) & (face >= 0)
        out[here] = phong(p[here], n[here], -d[here], lights, mat, c_amb, visible[here])
    return out, face, margin
