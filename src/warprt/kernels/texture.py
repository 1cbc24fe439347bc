"""A material colour's texture at a hit: the slot's uv map, then the image's bilinear texel read from
SceneData.texels (Warp's CPU wp.Texture2D sampler's arithmetic, over an array: the same texels to the bit,
and differentiable in them), or the procedural checker."""

from __future__ import annotations

from .._warp import wp
from ..geometry import CHECKER, TEXTURE_CLAMP, TEXTURE_MIRROR, TEXTURE_WRAP, UNTEXTURED, TextureSlot


@wp.func
def texture_coord(c: float, mode: int) -> float:
    """Warp's CPU sampler's reduction of a normalised coordinate (cpu_texture_normalized_coord, Warp 1.19
    native/texture.h): fmodf by the period (1; 2 mirrored), made positive; clamped coordinates as given."""
    if mode == wp.static(TEXTURE_WRAP) or mode == wp.static(TEXTURE_MIRROR):
        period = 1.0
        if mode == wp.static(TEXTURE_MIRROR):
            period = 2.0
        c = wp.mod(c, period)
        if c < 0.0:
            c = c + period
    return c


@wp.func
def texel_index(i: int, size: int, mode: int) -> int:
    """Warp's CPU sampler's texel index for an axis of ``size`` texels (cpu_apply_address_mode_index):
    repeated, clamped, or mirrored with period 2 size."""
    if mode == wp.static(TEXTURE_CLAMP):
        return wp.clamp(i, 0, size - 1)
    if mode == wp.static(TEXTURE_MIRROR):
        m = i % (2 * size)
        if m < 0:
            m = m + 2 * size
        if m >= size:
            m = 2 * size - m - 1
        return m
    m = i % size
    if m < 0:
        m = m + size
    return m


@wp.func
def bilinear(texels: wp.array(dtype=wp.vec3), offset: int, width: int, height: int, wrap_u: int, wrap_v: int,
             q: wp.vec2) -> wp.vec3:
    """The bilinear texel at normalised coordinates q of a width x height RGB image stored row by row
    (row 0 at v = 0) from ``offset`` in ``texels``: Warp's CPU wp.texture_sample of a LINEAR Texture2D
    (cpu_sample_2d_channel_at_level), its arithmetic in the same order (the same value to the bit,
    tests/grad/test_texture_gradients.py), differentiable in the texels and in q (wp.texture_sample gives texels no
    adjoint). CUDA's hardware filter, whose weights have 8 bits, is not used: the GPU reads the CPU's texels."""
    tx = texture_coord(q[0], wrap_u) * float(width) - 0.5
    ty = texture_coord(q[1], wrap_v) * float(height) - 0.5
    if wrap_u == wp.static(TEXTURE_CLAMP):
        tx = wp.max(0.0, wp.min(tx, float(width - 1)))
    if wrap_v == wp.static(TEXTURE_CLAMP):
        ty = wp.max(0.0, wp.min(ty, float(height - 1)))
    x0 = int(wp.floor(tx))
    y0 = int(wp.floor(ty))
    fx = tx - float(x0)
    fy = ty - float(y0)
    xa = texel_index(x0, width, wrap_u)
    xb = texel_index(x0 + 1, width, wrap_u)
    ya = texel_index(y0, height, wrap_v)
    yb = texel_index(y0 + 1, height, wrap_v)
    v00 = texels[offset + ya * width + xa]
    v10 = texels[offset + ya * width + xb]
    v01 = texels[offset + yb * width + xa]
    v11 = texels[offset + yb * width + xb]
    v0 = v00 * (1.0 - fx) + v10 * fx
    v1 = v01 * (1.0 - fx) + v11 * fx
    return v0 * (1.0 - fy) + v1 * fy


@wp.func
def texel(texels: wp.array(dtype=wp.vec3), slot: TextureSlot, uv: wp.vec2) -> wp.vec3:
    """What the slot multiplies its colour by at surface coordinates uv: 1 when untextured, c0 or c1
    on alternate unit squares of the mapped uv for the checker, else the image's bilinear texel."""
    if slot.image == wp.static(UNTEXTURED):
        return wp.vec3(1.0)
    p = wp.vec3(uv[0], uv[1], 1.0)
    q = wp.vec2(wp.dot(slot.u_map, p), wp.dot(slot.v_map, p))
    if slot.image == wp.static(CHECKER):
        # floor(u') + floor(v') even or odd; floats hold those integers exactly below 2^24.
        half = (wp.floor(q[0]) + wp.floor(q[1])) * 0.5
        if half == wp.floor(half):
            return slot.c0
        return slot.c1
    return bilinear(texels, slot.offset, slot.width, slot.height, slot.wrap[0], slot.wrap[1], q)
