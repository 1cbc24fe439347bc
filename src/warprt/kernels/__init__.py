"""The Warp functions and kernels, one concept a file:

    camera.py (the tracer's and the rasterizer's cameras, sample positions), triangle.py (a face's
    vertices, normal and Woop test), interaction.py (the hit record, its error bound, the ray offset,
    reflect), shading.py (Phong), shadow.py (whether a shadow ray is blocked: the BVH's any-hit query or
    the light-space grid), trace.py (the Whitted kernel), clip.py and raster.py (the Z-buffer:
    Fragments), hybrid.py (where the Z-buffer's first hit is the tracer's), mirror.py (a reflection ray's
    first hit from a planar mirror's virtual camera), zbuffer_shade.py.
"""

from .._warp import init_warp, wp
from .camera import CameraData, RasterCamera, camera_data, camera_ray, raster_camera, sample_offset
from .clip import CLIP_SCALE
from .hybrid import MARGIN_PX, TIE_REL, uncertain, uncertain_np
from .mirror import MARGIN_PX as MIRROR_MARGIN_PX, MAX_BOUNCES, MirrorHit, Mirrors, gather_kernel, mirror_chain, mirror_hit, probe_kernel
from .interaction import OFFSET_SCALE, Surface, hit_point_error, make_surface, offset_ray_origin, reflect
from .raster import Fragments, count_kernel, fill_kernel, project_kernel, raster_kernel
from .shading import ShadeResult, make_shade, phong_diffuse, phong_specular
from .shadow import cube_cell, grid_occluded, make_occluded
from .trace import make_trace_kernel, primary_faces_kernel, tile_order_pixel
from .triangle import query_normal, triangle, unit_normal, woop_hit
from .zbuffer_shade import make_shade_kernel

__all__ = ["CLIP_SCALE", "CameraData", "Fragments", "MARGIN_PX", "OFFSET_SCALE", "RasterCamera", "ShadeResult", "Surface",
           "MAX_BOUNCES", "MIRROR_MARGIN_PX", "MirrorHit", "Mirrors", "TIE_REL", "camera_data", "camera_ray", "count_kernel", "cube_cell", "fill_kernel", "gather_kernel", "grid_occluded", "hit_point_error", "init_warp",
           "make_occluded", "make_shade", "make_shade_kernel", "make_surface", "make_trace_kernel", "mirror_chain", "mirror_hit", "offset_ray_origin", "phong_diffuse",
           "phong_specular", "primary_faces_kernel", "probe_kernel", "project_kernel", "query_normal", "raster_camera", "raster_kernel",
           "reflect", "sample_offset", "tile_order_pixel", "triangle", "uncertain", "uncertain_np", "unit_normal",
           "woop_hit", "wp"]
