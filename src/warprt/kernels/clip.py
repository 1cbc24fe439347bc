"""Triangles clipped against the plane just in front of the eye, and projected to continuous pixel
coordinates with the tracer's own camera (float64).

Near plane: the tracer's primary rays start at the eye and report every hit with t >= 0, so it draws
geometry between the eye and the image plane at d_f = near. Clipping at z = -near, as OpenGL does,
would cut exactly that away; the rasterizer clips at z = -CLIP_SCALE R instead (R bounds the distance
of every vertex from the eye), which loses only what lies within about 1e-6 R of the eye. Screen
coordinates are float64, so vertices clipped that close to the eye still rasterize exactly.
"""

from __future__ import annotations

from .._warp import wp
from .camera import RasterCamera

CLIP_SCALE = 1.0e-6


@wp.struct
class ClipVertex:
    c: wp.vec3d  # camera coordinates (p.x_e, p.y_e, -p.z_e): the last is the depth in front of the eye
    uv: wp.vec2  # Warp's barycentrics of the original triangle: p = p0 u + p1 v + p2 (1 - u - v)


@wp.struct
class Polygon:
    """A triangle after clipping against the plane z = z_clip: n = 0, 3 or 4 vertices, in order."""

    n: int
    v0: ClipVertex
    v1: ClipVertex
    v2: ClipVertex
    v3: ClipVertex


@wp.struct
class ScreenVertex:
    x: wp.float64  # continuous pixel coordinates, y up
    y: wp.float64
    iz: wp.float64  # 1 / depth: linear in screen space, so it interpolates exactly
    uv: wp.vec2


@wp.func
def lex_less(a: wp.vec3d, b: wp.vec3d) -> bool:
    if a[0] != b[0]:
        return a[0] < b[0]
    if a[1] != b[1]:
        return a[1] < b[1]
    return a[2] < b[2]


@wp.func
def clip_vertex(c: RasterCamera, p: wp.vec3, uv: wp.vec2) -> ClipVertex:
    """Camera coordinates of a point: (q.x_e, q.y_e, -q.z_e), q = p - eye, exact in float64 (both are
    float32 values) unless their magnitudes differ by more than 2^29."""
    q = wp.vec3d(wp.float64(p[0]), wp.float64(p[1]), wp.float64(p[2])) - c.eye
    out = ClipVertex()
    out.c = wp.vec3d(wp.dot(q, c.x_e), wp.dot(q, c.y_e), -wp.dot(q, c.z_e))
    out.uv = uv
    return out


@wp.func
def clip_edge(a: ClipVertex, b: ClipVertex, z_clip: wp.float64) -> ClipVertex:
    """Where the edge a-b crosses z = z_clip. Computed from the lexicographically smaller endpoint,
    so two triangles sharing the edge get the same point and the clipped mesh stays watertight."""
    p = a
    q = b
    if lex_less(b.c, a.c):
        p = b
        q = a
    t = (z_clip - p.c[2]) / (q.c[2] - p.c[2])
    out = ClipVertex()
    out.c = wp.vec3d(p.c[0] + t * (q.c[0] - p.c[0]), p.c[1] + t * (q.c[1] - p.c[1]), z_clip)
    out.uv = p.uv + float(t) * (q.uv - p.uv)
    return out


@wp.func
def clip_triangle(c: RasterCamera, q0: wp.vec3, q1: wp.vec3, q2: wp.vec3) -> Polygon:
    """Sutherland-Hodgman against the one plane z = z_clip, in camera space (before the divide), of the
    triangle q0 q1 q2 (kernels/triangle.py)."""
    a = clip_vertex(c, q0, wp.vec2(1.0, 0.0))
    b = clip_vertex(c, q1, wp.vec2(0.0, 1.0))
    d = clip_vertex(c, q2, wp.vec2(0.0, 0.0))
    in_a = a.c[2] >= c.z_clip
    in_b = b.c[2] >= c.z_clip
    in_d = d.c[2] >= c.z_clip
    inside = int(in_a) + int(in_b) + int(in_d)
    out = Polygon()
    out.n = 0
    if inside == 3:
        out.n = 3
        out.v0 = a
        out.v1 = b
        out.v2 = d
    elif inside == 1:
        # Rotate (keeping the winding) so the inside vertex comes first: (first, first-next, prev-first).
        p0 = a
        p1 = b
        p2 = d
        if in_b:
            p0 = b
            p1 = d
            p2 = a
        elif in_d:
            p0 = d
            p1 = a
            p2 = b
        out.n = 3
        out.v0 = p0
        out.v1 = clip_edge(p0, p1, c.z_clip)
        out.v2 = clip_edge(p2, p0, c.z_clip)
    elif inside == 2:
        # Rotate so the outside vertex comes last: a quad (p0, p1, p1-p2, p2-p0).
        p0 = a
        p1 = b
        p2 = d
        if not in_a:
            p0 = b
            p1 = d
            p2 = a
        elif not in_b:
            p0 = d
            p1 = a
            p2 = b
        out.n = 4
        out.v0 = p0
        out.v1 = p1
        out.v2 = clip_edge(p1, p2, c.z_clip)
        out.v3 = clip_edge(p2, p0, c.z_clip)
    return out


@wp.func
def project(c: RasterCamera, v: ClipVertex) -> ScreenVertex:
    """(X, Y) = (c_x + f_x x/z, c_y + f_y y/z): the inverse of the tracer's camera_ray."""
    out = ScreenVertex()
    out.iz = wp.float64(1.0) / v.c[2]
    out.x = c.c_x + c.f_x * v.c[0] * out.iz
    out.y = c.c_y + c.f_y * v.c[1] * out.iz
    out.uv = v.uv
    return out
