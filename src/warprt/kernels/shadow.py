"""Whether a shadow ray is blocked: the one question shading asks, answered by the BVH's any-hit query or
by the light-space grid (geometry/shadow_grid.py), which gives the very same answer with fewer tests."""

from __future__ import annotations

import functools

from .._warp import wp
from ..geometry import SceneData
from .triangle import triangle, woop_hit


@wp.func
def cube_cell(x: wp.vec3, n: int) -> wp.vec2i:
    """(face, row * n + col) of direction x on the cube map: face 2 axis + (1 if negative), the cell
    from (u, v) = (x_b, x_c) / |x_a| on [-1, 1], b and c the next two axes."""
    ax = wp.abs(x)
    a = int(0)
    if ax[1] > ax[a]:
        a = 1
    if ax[2] > ax[a]:
        a = 2
    face = 2 * a
    if x[a] < 0.0:
        face += 1
    inv = 1.0 / ax[a]
    u = x[(a + 1) % 3] * inv
    v = x[(a + 2) % 3] * inv
    iu = wp.clamp(int((u + 1.0) * 0.5 * float(n)), 0, n - 1)
    iv = wp.clamp(int((v + 1.0) * 0.5 * float(n)), 0, n - 1)
    return wp.vec2i(face, iv * n + iu)


@wp.func
def grid_occluded(s: SceneData, l: int, o: wp.vec3, d: wp.vec3, max_t: float) -> bool:
    """wp.mesh_query_ray_anyhit(s.mesh, o, d, max_t) for a ray from o to light l, from the grid: the
    query's own leaf test (Woop's, 0 <= t < max_t) on the triangles of o's cell nearer the light than o,
    nearest first, stopping at the first hit."""
    g = s.shadow_grid
    if g.light_ok[l] == 0:
        return wp.mesh_query_ray_anyhit(s.mesh, o, d, max_t)
    x = o - s.light_pos[l]
    r = wp.length(x)
    if not (r > 0.0):
        return wp.mesh_query_ray_anyhit(s.mesh, o, d, max_t)
    cell = cube_cell(x, g.n)
    first = g.start[(l * 6 + cell[0]) * g.n * g.n + cell[1]]
    last = g.start[(l * 6 + cell[0]) * g.n * g.n + cell[1] + 1]
    reach = r * 1.00001 + g.delta  # a blocker comes nearer the light than o, up to float32 rounding and delta
    for e in range(first, last):
        entry = g.entries[e]
        if entry.dmin > reach:
            return False
        p0, p1, p2 = triangle(s, entry.tri)
        t = woop_hit(o, d, p0, p1, p2)[0]
        if t >= 0.0 and t < max_t:
            return True
    return False


@functools.cache
def make_occluded(grid: bool):
    """occluded(s, l, o, d, max_t): the BVH's any-hit query, or with ``grid`` the grid's same answer."""

    @wp.func
    def occluded(s: SceneData, l: int, o: wp.vec3, d: wp.vec3, max_t: float) -> bool:
        if wp.static(grid):
            return grid_occluded(s, l, o, d, max_t)
        return wp.mesh_query_ray_anyhit(s.mesh, o, d, max_t)

    return occluded
