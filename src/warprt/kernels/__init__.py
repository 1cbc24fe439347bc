"""The Warp functions and kernels, one concept a file:

    camera.py (the tracer's and the rasterizer's cameras, sample positions), triangle.py (a face's
    vertices, normal and Woop test), interaction.py (the hit record, its error bound, the ray offset,
    reflect), texture.py (a material colour's texture at a hit), shading.py (Phong), shadow.py (whether a
    shadow ray is blocked: the BVH's any-hit query or the light-space grid), dielectric.py (Fresnel, Snell,
    Beer), trace.py (the Whitted kernel and its ray tree), aov.py (what a first hit records besides
    colour), clip.py and raster.py (the Z-buffer: Fragments), hybrid.py (where the Z-buffer's first hit is
    the tracer's), mirror.py (a reflection ray's first hit from a planar mirror's virtual camera),
    zbuffer_shade.py.
"""

from .._warp import init_warp, wp
from .aov import AovBuffers, aov_buffers, aov_bytes, aov_sums, empty_aov_buffers, id_sample, make_record_first_hit
from .camera import CameraData, RasterCamera, camera_data, camera_ray, raster_camera, sample_offset
from .clip import CLIP_SCALE
from .dielectric import beer, beer_forever, fresnel_dielectric, refract
from .hybrid import MARGIN_PX, TIE_REL, uncertain, uncertain_np
from .mirror import MARGIN_PX as MIRROR_MARGIN_PX, MAX_BOUNCES, MirrorHit, Mirrors, gather_kernel, mirror_chain, mirror_hit, probe_kernel
from .interaction import OFFSET_SCALE, Surface, hit_point_error, make_surface, offset_ray_origin, reflect
from .raster import Fragments, count_kernel, fill_kernel, project_kernel, raster_kernel
from .shading import Coefficients, ShadeResult, make_coefficients, make_shade, phong_diffuse, phong_specular
from .shadow import cube_cell, grid_occluded, make_occluded
from .texture import texel
from .trace import MAX_TREE_DEPTH, STACK_SIZES, make_trace_kernel, stack_size, tile_order_pixel
from .triangle import query_normal, triangle, unit_normal, woop_hit
from .zbuffer_shade import make_shade_kernel

__all__ = ["aov_buffers", "aov_bytes", "aov_sums", "AovBuffers", "beer", "beer_forever", "camera_data", "camera_ray",
           "CameraData", "CLIP_SCALE", "Coefficients", "count_kernel", "cube_cell", "empty_aov_buffers",
           "fill_kernel", "Fragments", "fresnel_dielectric", "gather_kernel", "grid_occluded", "hit_point_error",
           "id_sample", "init_warp", "make_coefficients", "make_occluded", "make_record_first_hit", "make_shade",
           "make_shade_kernel", "make_surface", "make_trace_kernel", "MARGIN_PX", "MAX_BOUNCES", "MAX_TREE_DEPTH",
           "mirror_chain", "mirror_hit", "MIRROR_MARGIN_PX", "MirrorHit", "Mirrors", "offset_ray_origin",
           "OFFSET_SCALE", "phong_diffuse", "phong_specular", "probe_kernel",
           "project_kernel", "query_normal", "raster_camera", "raster_kernel", "RasterCamera", "reflect", "refract",
           "sample_offset", "ShadeResult", "stack_size", "STACK_SIZES", "Surface", "texel", "TIE_REL",
           "tile_order_pixel", "triangle", "uncertain", "uncertain_np", "unit_normal", "woop_hit", "wp"]
