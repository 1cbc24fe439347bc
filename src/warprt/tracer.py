"""The Whitted tracer: one Warp kernel per effect set, launched over bands of image rows.

Per pixel and sample: a camera ray, nearest hit (wp.mesh_query_ray), local Phong shading with
shadow rays (wp.mesh_query_ray_anyhit), then an iterative mirror bounce weighted by k_r.
"""

from __future__ import annotations

from ._warp import wp

from .geometry import SceneData
from .shading import hit_point_error, make_shade, offset_ray_origin


@wp.struct
class CameraData:
    """The seed's camera basis and image-plane size, in camera-relative space (eye at 0)."""

    x_e: wp.vec3
    y_e: wp.vec3
    z_e: wp.vec3
    d_f: float
    h: float
    w: float
    width: int
    height: int


def camera_data(basis) -> CameraData:
    c = CameraData()
    c.x_e, c.y_e, c.z_e = (wp.vec3(*map(float, v)) for v in (basis.x_e, basis.y_e, basis.z_e))
    c.d_f, c.h, c.w = float(basis.d_f), float(basis.h), float(basis.w)
    c.width, c.height = int(basis.width), int(basis.height)
    return c


@wp.func
def camera_ray(c: CameraData, x: int, row: int, sx: float, sy: float) -> wp.vec3:
    """Unit direction d = -d_f z_e + h((y+sy)/h_p - 1/2) y_e + w((x+sx)/w_p - 1/2) x_e,
    y = h_p - 1 - row counted from the bottom, so row 0 of the image is the top."""
    y = float(c.height - 1 - row)
    d = (-c.d_f) * c.z_e + c.h * ((y + sy) / float(c.height) - 0.5) * c.y_e \
        + c.w * ((float(x) + sx) / float(c.width) - 0.5) * c.x_e
    return wp.normalize(d)


@wp.struct
class Surface:
    p: wp.vec3  # hit point, p0 u + p1 v + p2 (1 - u - v)
    err: wp.vec3  # its absolute error bound
    ng: wp.vec3  # geometric normal, turned to face the incoming ray
    n: wp.vec3  # shading normal, on the same side
    material: int


@wp.func
def unit_normal(p0: wp.vec3, p1: wp.vec3, p2: wp.vec3) -> wp.vec3:
    """normalize(cross(p1 - p0, p2 - p0)), scaled first by its largest component. Warp's query
    normalizes the raw cross product, whose squared length underflows to 0 for triangles under
    about 1e-10 across and overflows above about 1e10: it then reports a zero normal."""
    e = wp.cross(p1 - p0, p2 - p0)
    big = wp.max(wp.abs(e))
    if big > 0.0:
        e = e / big
    return wp.normalize(e)


_surface_cache: dict = {}


def make_surface(smooth: bool):
    """The hit record for face f at barycentrics (u, v), seen along direction d."""
    if smooth in _surface_cache:
        return _surface_cache[smooth]

    @wp.func
    def surface(s: SceneData, f: int, u: float, v: float, face_normal: wp.vec3, d: wp.vec3) -> Surface:
        i0 = s.indices[f * 3 + 0]
        i1 = s.indices[f * 3 + 1]
        i2 = s.indices[f * 3 + 2]
        p0 = s.points[i0]
        p1 = s.points[i1]
        p2 = s.points[i2]
        w = 1.0 - u - v
        out = Surface()
        out.p = p0 * u + p1 * v + p2 * w
        out.err = hit_point_error(p0, p1, p2, u, v, w)
        ng = face_normal
        if not (wp.length(ng) > 0.0):
            ng = unit_normal(p0, p1, p2)
        side = 1.0
        # Two-sided surfaces: Warp's face normal follows the winding; turn it to face the ray.
        if wp.dot(ng, d) > 0.0:
            side = -1.0
        out.ng = ng * side
        out.n = out.ng
        if wp.static(smooth):
            if s.tri_smooth[f] != 0:
                ns = s.normals[i0] * u + s.normals[i1] * v + s.normals[i2] * w
                if wp.length(ns) > 0.0:
                    out.n = wp.normalize(ns) * side
        out.material = s.tri_material[f]
        return out

    _surface_cache[smooth] = surface
    return surface


@wp.func
def tile_order_pixel(i: int, width: int, height: int, tile_w: int, tile_h: int) -> wp.vec2i:
    """The (x, row) of the i-th pixel when the image is walked tile by tile: strips of tile_h rows
    top to bottom, each cut into tiles tile_w wide, left to right, row-major inside a tile; the
    right column and bottom strip of tiles may be narrower. Neighbouring rays then stay together
    in a band, so they walk the same BVH nodes while those are in cache."""
    strip = i / (width * tile_h)
    local = i - strip * width * tile_h
    th = wp.min(tile_h, height - strip * tile_h)
    col = local / (tile_w * th)
    within = local - col * tile_w * th
    tw = wp.min(tile_w, width - col * tile_w)
    return wp.vec2i(col * tile_w + within % tw, strip * tile_h + within / tw)


@wp.func_native("""
float t, u, v, sign;
if (wp::intersect_ray_tri_woop(o, d, p0, p1, p2, t, u, v, sign, nullptr) && t >= 0.0f)
    return wp::vec3(t, u, v);
return wp::vec3(-1.0f, 0.0f, 0.0f);
""")
def woop_hit(o: wp.vec3, d: wp.vec3, p0: wp.vec3, p1: wp.vec3, p2: wp.vec3) -> wp.vec3:
    """(t, u, v) of the ray o + t d on one triangle, t = -1 for a miss: the very test, Woop's watertight
    one, that wp.mesh_query_ray applies to each triangle of a BVH leaf, so on the triangle that query
    returns it gives the query's t, u and v to the bit."""
    ...


_kernel_cache: dict = {}


def make_trace_kernel(fx, raster_primary: bool = False):
    """The kernel for one EffectSet; code for disabled effects is removed by wp.static. With
    raster_primary (hybrid rendering), a sample's first hit is the Z-buffer's visible triangle, tested
    with the ray query's own triangle test, wherever the rasterizer's answer is certain to be the
    tracer's (zbuffer.uncertain); every other sample is traced. The image is the traced image, to
    the bit; shadows and reflections are traced as always."""
    key = (fx, raster_primary)
    if key in _kernel_cache:
        return _kernel_cache[key]
    from .zbuffer import uncertain  # zbuffer builds on this module
    shade = make_shade(fx)
    surface = make_surface(fx.smooth)
    REFLECTION, SUPERSAMPLING, RASTER = fx.reflection, fx.supersampling, raster_primary

    @wp.kernel(module="unique", enable_backward=False)
    def trace(s: SceneData, c: CameraData, max_depth: int, k: int, first: int, tile_w: int, tile_h: int,
              raster_face: wp.array(dtype=wp.int32), raster_depth: wp.array(dtype=wp.float64),
              raster_near: wp.array(dtype=wp.float64),
              image: wp.array(dtype=wp.vec3), counts: wp.array(dtype=wp.vec3i)):
        i = first + wp.tid()  # position in tile order; the image itself is row-major
        xy = tile_order_pixel(i, c.width, c.height, tile_w, tile_h)
        x = xy[0]
        row = xy[1]
        pixel = row * c.width + x
        total = wp.vec3(0.0)
        shadow_rays = int(0)
        reflection_rays = int(0)
        samples = int(1)
        if wp.static(SUPERSAMPLING):
            samples = k * k
        for sample in range(samples):
            sx = float(0.5)
            sy = float(0.5)
            if wp.static(SUPERSAMPLING):
                sx = (float(sample % k) + 0.5) / float(k)
                sy = (float(sample / k) + 0.5) / float(k)
            o = wp.vec3(0.0)
            d = camera_ray(c, x, row, sx, sy)
            weight = wp.vec3(1.0)
            color = wp.vec3(0.0)
            depth = int(0)
            while depth < max_depth:
                f = int(-1)
                u = float(0.0)
                v = float(0.0)
                face_normal = wp.vec3(0.0)
                rasterized = False
                if wp.static(RASTER):
                    n_s = pixel * samples + sample
                    if depth == 0 and not uncertain(raster_depth[n_s], raster_near[n_s]):
                        rasterized = True
                        f = raster_face[n_s]
                        if f >= 0:
                            p0 = s.points[s.indices[f * 3 + 0]]
                            p1 = s.points[s.indices[f * 3 + 1]]
                            p2 = s.points[s.indices[f * 3 + 2]]
                            h = woop_hit(o, d, p0, p1, p2)
                            if h[0] >= 0.0:
                                u = h[1]
                                v = h[2]
                                face_normal = wp.normalize(wp.cross(p1 - p0, p2 - p0))  # as the query reports it
                            else:  # never seen: a certain sample is well inside its triangle
                                rasterized = False
                                f = -1
                if not rasterized:
                    q = wp.mesh_query_ray(s.mesh, o, d, 1.0e30)
                    if q.result:
                        f = q.face
                        u = q.u
                        v = q.v
                        face_normal = q.normal
                if f < 0:
                    color = color + wp.cw_mul(weight, s.background)
                    break
                hit = surface(s, f, u, v, face_normal, d)
                r = shade(s, hit.material, hit.p, hit.err, hit.ng, hit.n, -d)
                color = color + wp.cw_mul(weight, r.color)
                shadow_rays += r.shadow_rays
                depth += 1
                if wp.static(REFLECTION):
                    kr = s.kr[hit.material]
                    if depth < max_depth and wp.max(kr) > 0.0:
                        weight = wp.cw_mul(weight, kr)
                        d = wp.normalize(d - 2.0 * wp.dot(d, hit.n) * hit.n)
                        o = offset_ray_origin(hit.p, hit.err, hit.ng, d)
                        reflection_rays += 1
                        continue
                break
            total = total + color
        image[pixel] = total / float(samples)
        counts[i] = wp.vec3i(samples, shadow_rays, reflection_rays)  # in tile order: a band's counts are contiguous

    _kernel_cache[key] = trace
    return trace
