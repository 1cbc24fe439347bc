"""A reflection ray's first hit from a virtual camera: the rasterized unfolded scene of its chain of planar
mirrors (geometry/planar.py), taken only where it must be the BVH query's, and re-derived with Woop's test.

A ray's answer comes from the raster only where, beyond the hybrid's certainty (no edge within the
raster's margin, no rival within TIE_REL in depth): the surface seen lies beyond the mirror by more
than TIE_REL, the ray is not grazing its mirror (|d.n| > GRAZE), the float32 ray strays from its ideal
unfolded line by less than MAX_DEV_PX (measured per ray: the error-bound offset off a large floor moves
it up to 0.016 px, which is why the mirrors' raster margin is MARGIN_PX = 0.03, not the hybrid's 0.01),
it starts on its mirror's front, and Woop's test finds no hit on the triangle it leaves. The rest of the
margin covers Woop's own rounding (~4e-4 px) and the unfolded float32 vertices' (~1e-4 px).
"""

from __future__ import annotations

from .._warp import wp
from ..geometry import SceneData
from .camera import CameraData, RasterCamera, camera_ray, sample_position
from .hybrid import TIE_REL, uncertain
from .interaction import make_surface, reflect, spawn_ray
from .raster import Fragments
from .triangle import triangle, woop_hit

MARGIN_PX = 0.03
MAX_DEV_PX = 0.027
GRAZE = 1.0e-3
NO_CHAIN = -2  # a ray whose bounces so far were not all off planar mirrors with a raster
FROM_CAMERA = -1  # no bounce yet
MAX_BOUNCES = 8  # the longest chain of planar mirrors with a virtual camera
flat_surface = make_surface(False)  # the probe's hit record: position, error bound, face normal


@wp.struct
class Mirrors:
    """What the trace kernel reads of a frame's virtual cameras: per chain (of up to MAX_BOUNCES planar
    groups) its planes and the raster of its unfolded scene, stored for the 16x16 tiles its rays cover."""

    group: wp.array(dtype=wp.int32)  # per triangle: its planar group, -1 for none
    first_chain: wp.array(dtype=wp.int32)  # per group: the chain of a ray that bounced off it first, or NO_CHAIN
    next_chain: wp.array(dtype=wp.int32)  # chain c, then group g: next_chain[c * groups + g], or NO_CHAIN
    groups: int
    plane: wp.array(dtype=wp.vec4d)  # chain c's planes in bounce order: plane[MAX_BOUNCES c + j]
    level: wp.array(dtype=wp.int32)  # its bounces
    side: wp.array(dtype=wp.float64)  # the last plane's side the chain's rays start on (+1 or -1)
    tile_slot: wp.array(dtype=wp.int32)  # chain c, tile t: tile_slot[c * tiles + t], or -1 (not rasterized)
    tiles: int
    tiles_x: int
    tile: int
    face: wp.array(dtype=wp.int32)  # per stored sample: the parent's face seen, -1 for none
    inv_depth: wp.array(dtype=wp.float64)
    rival_inv_depth: wp.array(dtype=wp.float64)
    camera: RasterCamera  # the ideal lines, float64
    samples: int
    k: int
    pixel_angle: wp.float64  # radians per pixel at the image's corner, where a pixel is smallest
    decided: wp.array(dtype=wp.int32)  # per pixel in tile order: reflection rays decided here


@wp.struct
class MirrorHit:
    face: int  # -1: a certain miss
    u: float
    v: float
    found: bool  # False: the BVH must answer


@wp.func
def mirror_chain(m: Mirrors, chain: int, f: int) -> int:
    """The chain of the ray reflected off face f by a ray of ``chain`` (FROM_CAMERA for a camera ray)."""
    g = m.group[f]
    if g < 0 or chain == NO_CHAIN:
        return NO_CHAIN
    if chain == FROM_CAMERA:
        return m.first_chain[g]
    return m.next_chain[chain * m.groups + g]


@wp.func
def mirrored(p: wp.vec3d, plane: wp.vec4d) -> wp.vec3d:
    n = wp.vec3d(plane[0], plane[1], plane[2])
    return p - wp.float64(2.0) * (wp.dot(n, p) - plane[3]) * n


@wp.func
def mirror_hit(s: SceneData, m: Mirrors, level: int, o: wp.vec3, d: wp.vec3, chain: int, x: int, row: int,
               sample: int, src: int) -> MirrorHit:
    """The first hit of the reflection ray (o, d) of ray level ``level`` and mirror ``chain``, at pixel
    (x, row) and sample ``sample``, leaving face ``src``: found where the chain's raster must give
    wp.mesh_query_ray's answer, with that query's own (face, u, v)."""
    out = MirrorHit()
    out.face = -1
    out.found = False
    if chain < 0 or m.level[chain] != level:
        return out
    c = m.camera
    y = c.height - 1 - row
    slot = m.tile_slot[chain * m.tiles + (y / m.tile) * m.tiles_x + x / m.tile]
    if slot < 0:
        return out
    local = ((y % m.tile) * m.tile + x % m.tile) * m.samples + sample
    n_s = slot * m.tile * m.tile * m.samples + local
    inv_depth = m.inv_depth[n_s]
    if uncertain(inv_depth, m.rival_inv_depth[n_s]):
        return out
    last = m.plane[wp.static(MAX_BOUNCES) * chain + level - 1]
    n_last = wp.vec3(float(last[0]), float(last[1]), float(last[2]))
    if wp.abs(wp.dot(d, n_last)) <= wp.static(GRAZE):
        return out
    # Unfold the float32 ray (last bounce first) and measure it against the sample's ideal line.
    po = wp.vec3d(wp.float64(o[0]), wp.float64(o[1]), wp.float64(o[2]))
    if (wp.dot(wp.vec3d(last[0], last[1], last[2]), po) - last[3]) * m.side[chain] <= wp.float64(0.0):
        return out
    pd = wp.vec3d(wp.float64(d[0]), wp.float64(d[1]), wp.float64(d[2]))
    zero = wp.vec4d(wp.float64(0.0), wp.float64(0.0), wp.float64(0.0), wp.float64(0.0))
    for j in range(level):
        plane = m.plane[wp.static(MAX_BOUNCES) * chain + level - 1 - j]
        po = mirrored(po, plane)
        pd = mirrored(pd, wp.vec4d(plane[0], plane[1], plane[2], wp.float64(0.0)))
    k = wp.where(m.samples > 1, m.k, 1)  # the raster's strata per axis
    step = wp.float64(1.0) / wp.float64(k)
    ideal = wp.normalize((sample_position(x, sample % k, step) - c.c_x) / c.f_x * c.x_e
                         + (sample_position(y, sample / k, step) - c.c_y) / c.f_y * c.y_e - c.z_e)
    rel = po - c.eye
    along = wp.dot(rel, ideal)
    z_mirror = -wp.dot(rel, c.z_e)  # the depth of the mirror point, as the raster measures depth
    if not (z_mirror > wp.float64(4.0) * c.z_clip and along > wp.float64(0.0)):  # clear of the raster's clip plane
        return out
    # the surface seen lies beyond the mirror by more than a depth tie
    if not (inv_depth < (wp.float64(1.0) - wp.float64(TIE_REL)) / z_mirror):
        return out
    pd = wp.normalize(pd)
    stray = wp.length(rel - along * ideal) / wp.length(rel) + wp.length(pd - wp.dot(pd, ideal) * ideal)
    if not (stray < wp.float64(MAX_DEV_PX) * m.pixel_angle):
        return out
    p0, p1, p2 = triangle(s, src)
    if woop_hit(o, d, p0, p1, p2)[0] >= 0.0:  # a self-hit: the BVH's to find
        return out
    f = m.face[n_s]
    if f >= 0:
        q0, q1, q2 = triangle(s, f)
        h = woop_hit(o, d, q0, q1, q2)
        if h[0] < 0.0:
            return out
        out.u = h[1]
        out.v = h[2]
    out.face = f
    out.found = True
    return out


@wp.kernel(enable_backward=False)
def gather_kernel(frags: Fragments, tile_slot: wp.array(dtype=wp.int32), chain: int, tiles: int, tiles_x: int,
                  tile: int, samples: int, width: int, height: int, source: wp.array(dtype=wp.int32),
                  stored: wp.array(dtype=wp.int32), face: wp.array(dtype=wp.int32), inv_depth: wp.array(dtype=wp.float64),
                  rival: wp.array(dtype=wp.float64)):
    """Copy a chain's raster, sample by sample of its stored tiles, into the Mirrors buffers (faces
    mapped back to the parent's), and clear those samples for the next chain: thread i is sample
    i % per_tile of tile stored[i / per_tile]."""
    i = wp.tid()
    per_tile = tile * tile * samples
    t = stored[i / per_tile]
    local = i % per_tile
    slot = tile_slot[chain * tiles + t]
    x = (t % tiles_x) * tile + (local / samples) % tile
    y = (t / tiles_x) * tile + (local / samples) / tile
    j = slot * per_tile + local
    face[j] = -1
    inv_depth[j] = wp.float64(0.0)
    rival[j] = wp.float64(0.0)
    if x < width and y < height:
        n = ((height - 1 - y) * width + x) * samples + local % samples
        f = frags.face[n]
        if f >= 0:
            face[j] = source[f]
        inv_depth[j] = frags.inv_depth[n]
        rival[j] = frags.rival_inv_depth[n]
        frags.face[n] = -1
        frags.inv_depth[n] = wp.float64(0.0)
        frags.rival_inv_depth[n] = wp.float64(0.0)


@wp.kernel(enable_backward=False)
def probe_kernel(s: SceneData, c: CameraData, group: wp.array(dtype=wp.int32), planes: wp.array(dtype=wp.vec4),
                 tile: int, tiles_x: int, per_side: int, bounces: int, first: int, out: wp.array2d(dtype=wp.int32)):
    """Which planar groups a few camera rays per raster tile bounce off, traced: out[i] = (tile, then per
    bounce the group and the side of its plane the ray meets it from, group -1 once the ray has left
    the planar mirrors, then how many of its queries hit something); per_side x per_side rays per tile."""
    i = first + wp.tid()
    per_tile = per_side * per_side
    t = i / per_tile
    j = i % per_tile
    step = tile / per_side
    x = (t % tiles_x) * tile + (j % per_side) * step + step / 2
    y = (t / tiles_x) * tile + (j / per_side) * step + step / 2
    out[i, 0] = t
    for level in range(bounces):
        out[i, 1 + 2 * level] = -1
    out[i, 1 + 2 * bounces] = 0
    if x < c.width and y < c.height:
        o = c.eye
        d = camera_ray(c, x, c.height - 1 - y, 0.5, 0.5)
        for level in range(bounces + 1):
            q = wp.mesh_query_ray(s.mesh, o, d, 1.0e30)
            if not q.result:
                break
            out[i, 1 + 2 * bounces] = level + 1
            if level == bounces:
                break
            g = group[q.face]
            if g < 0:
                break
            pl = planes[g]
            out[i, 1 + 2 * level] = g
            out[i, 2 + 2 * level] = wp.where(wp.dot(wp.vec3(pl[0], pl[1], pl[2]), o) > pl[3], 1, -1)
            hit = flat_surface(s, q.face, q.u, q.v, q.normal, d)
            ray = spawn_ray(hit, wp.normalize(reflect(d, hit.ng)))
            o = ray.o
            d = ray.d


@wp.kernel(enable_backward=False)
def total_kernel(values: wp.array(dtype=wp.int32), total: wp.array(dtype=wp.int64)):
    """total[0] += every values[i]: a per-sample count summed where it lives, so that a frame reads back
    8 bytes for the stats rather than one int per sample."""
    wp.atomic_add(total, 0, wp.int64(values[wp.tid()]))
