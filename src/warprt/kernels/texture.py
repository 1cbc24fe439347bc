"""A material colour's texture at a hit: the slot's uv map, then Warp's bilinear, repeating
wp.Texture2D sample (SceneData.textures) or the procedural checker."""

from __future__ import annotations

from .._warp import wp
from ..geometry import CHECKER, TextureSlot


@wp.func
def texel(textures: wp.array(dtype=wp.Texture2D), slot: TextureSlot, uv: wp.vec2) -> wp.vec3:
    """What the slot multiplies its colour by at surface coordinates uv: 1 when untextured, c0 or c1
    on alternate unit squares of the mapped uv for the checker, else the image's bilinear texel."""
    if slot.image == 0:
        return wp.vec3(1.0)
    p = wp.vec3(uv[0], uv[1], 1.0)
    q = wp.vec2(wp.dot(slot.u_map, p), wp.dot(slot.v_map, p))
    if slot.image == wp.static(CHECKER):
        # floor(u') + floor(v') even or odd; floats hold those integers exactly below 2^24.
        half = (wp.floor(q[0]) + wp.floor(q[1])) * 0.5
        if half == wp.floor(half):
            return slot.c0
        return slot.c1
    t = wp.texture_sample(textures[slot.image], q, dtype=wp.vec4)
    return wp.vec3(t[0], t[1], t[2])
