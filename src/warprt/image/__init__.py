"""The host side of a frame: launching bands (launch.py), the stats and their timer (stats.py), the
renderers and their policies (renderer.py), the Z-buffer's buffers (zbuffer.py), the planar mirrors'
virtual cameras (mirrors.py), the AOVs (aovs.py), memory (memory.py), image files (film.py) and the
progress line (progress.py).

Warp is imported on first use of a name that needs it: writing or reading an image does not.
"""

from .aovs import AOVS, check_aovs
from .film import (FORMATS as IMAGE_FORMATS, aov_paths, linear_to_srgb, partial_files, read_aovs, read_image, srgb_to_linear,
                   to_srgb8, write_image)
from .stats import RenderResult, RenderStats

_WARP_NAMES = {
    "renderer": ("DEFAULTS", "AUTO_RASTER_MAX_BYTES", "RASTER_BYTES_PER_SAMPLE", "RenderOptions", "cached_geometry",
                 "frame_geometry", "light_history", "raster_is_cheaper", "render", "render_zbuffer", "check_finite",
                 "shadows_from_grid"),
    "zbuffer": ("ZBuffer", "eye_on_surface"),
    "launch": ("bands_of", "default_threads", "launch_bands"),
    "mirrors": ("MirrorFrame",),
}

__all__ = ["AOVS", "IMAGE_FORMATS", "RenderResult", "RenderStats", "aov_paths", "check_aovs", "linear_to_srgb",
           "partial_files", "read_aovs", "read_image", "srgb_to_linear", "to_srgb8", "write_image", *(n for names in _WARP_NAMES.values() for n in names)]


def __getattr__(name):
    for module, names in _WARP_NAMES.items():
        if name in names:
            import importlib

            value = getattr(importlib.import_module(f".{module}", __name__), name)
            globals()[name] = value
            return value
    raise AttributeError(f"module 'warprt.image' has no attribute '{name}'")
