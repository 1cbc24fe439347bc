"""The samples a pixel takes: render.spp = k*k asks for a k x k stratified grid, taken with the
supersampling effect; without it, the pixel's centre alone."""

from __future__ import annotations

import math
from typing import NamedTuple


class SampleGrid(NamedTuple):
    k: int  # the side render.spp asks for (what the kernels read, with supersampling or not)
    side: int  # the side taken: k with supersampling, else 1

    @property
    def per_pixel(self) -> int:
        return self.side * self.side


def sample_grid(scene, fx) -> SampleGrid:
    """The grid a frame of ``scene`` with EffectSet ``fx`` takes in each pixel."""
    k = math.isqrt(scene.render.spp)
    return SampleGrid(k, k if fx.supersampling else 1)
