"""The host side of a frame: launching bands (launch.py), the stats (stats.py), the renderers and their
policies (renderer.py), the Z-buffer (zbuffer.py), the planar mirrors' virtual cameras (mirrors.py), the
AOVs (aovs.py), memory (memory.py), image files (film.py) and the progress line (progress.py).
"""

from .aovs import AOVS, check_aovs
from .film import aov_paths, partial_files, read_aovs, read_image, to_srgb8, write_image
from .launch import bands_of, default_threads, launch_bands
from .mirrors import MirrorFrame
from .renderer import (DEFAULTS, RenderOptions, cached_geometry, check_finite, frame_geometry, light_history,
                       raster_is_cheaper, render, render_zbuffer, shadows_from_grid)
from .stats import RenderResult, RenderStats
from .zbuffer import ZBuffer, eye_on_surface

__all__ = ["AOVS", "DEFAULTS", "MirrorFrame", "RenderOptions", "RenderResult", "RenderStats", "ZBuffer", "aov_paths",
           "bands_of", "cached_geometry", "check_aovs", "check_finite", "default_threads", "eye_on_surface",
           "frame_geometry", "launch_bands", "light_history", "partial_files", "raster_is_cheaper", "read_aovs",
           "read_image", "render", "render_zbuffer", "shadows_from_grid", "to_srgb8", "write_image"]
