"""The independent reference: any warprt Scene rendered by Mitsuba 3 with a Whitted integrator,
and the comparison (SSIM, PSNR, share of pixels off) that the accuracy suite and `warprt compare` use.

    from reference import compare
    result = compare(warprt.load_scene("scenes/cornell.toml"), width=160, height=120)
    aovs = render_mitsuba_aovs(scene)   # Mitsuba's aov integrator: depth, normals, position, uv, shape
"""

from .aov import render_mitsuba_aovs
from .compare import CompareResult, compare, side_by_side
from .mitsuba_whitted import MitsubaScene, Switches, mitsuba_variant, render_mitsuba
from .ray_tree import TreeResult, path_name, render_tree

__all__ = ["compare", "CompareResult", "mitsuba_variant", "MitsubaScene", "path_name", "render_mitsuba",
           "render_mitsuba_aovs", "render_tree", "side_by_side", "Switches", "TreeResult"]
