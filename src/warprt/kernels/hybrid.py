"""The hybrid's certainty rule: where the rasterizer's float64 answer must be the tracer's float32 one,
so that a sample's first hit may come from the Z-buffer and the image still be the traced image.

Uncertain are a sample within MARGIN_PX pixels of a triangle's edge, or two surfaces within TIE_REL of
each other in depth. Float32 rounding moves the tracer's rays by about 1e-4 pixel at 1024 pixels
across (a few ulp of the direction, 1e-7 rad, against 7.7e-4 rad per pixel at fovy 45) and its hit
distances by about 1e-6 relative; both margins are a hundred times that. The rasterizer records, per
sample, the inverse depth of the nearest such rival (raster.Fragments.rival_inv_depth).
"""

from __future__ import annotations

from .._warp import wp

MARGIN_PX = 1.0e-2
TIE_REL = 1.0e-4


@wp.func
def uncertain(inv_depth: wp.float64, rival_inv_depth: wp.float64) -> bool:
    """Whether the tracer may see another surface than the rasterizer at a sample: some surface near
    an edge there, or hidden by less than TIE_REL in depth, is about as near as the visible one
    (1/z at least (1 - TIE_REL) times the visible one's; inverse depth 0 where nothing is visible)."""
    return rival_inv_depth > wp.float64(0.0) and rival_inv_depth >= inv_depth * wp.float64(1.0 - TIE_REL)


def uncertain_np(inv_depth, rival_inv_depth):
    """uncertain() on NumPy arrays of samples."""
    return (rival_inv_depth > 0.0) & (rival_inv_depth >= inv_depth * (1.0 - TIE_REL))
