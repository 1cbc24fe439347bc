"""The Warp functions and kernels, one concept a file:

    camera.py (the tracer's and the rasterizer's cameras, sample positions), triangle.py (a face's
    vertices, normal and Woop test), interaction.py (the hit record, its error bound, the ray offset,
    reflect), texture.py (a material colour's texture at a hit), shading.py (Phong), shadow.py (whether a
    shadow ray is blocked: the BVH's any-hit query or the light-space grid), dielectric.py (Fresnel, Snell,
    Beer), trace.py (the Whitted kernel and its ray tree), grad.py and grad_tree.py (the gradient's record
    and differentiable replay: camera and mirror rays; the ray tree with glass), edges.py (the edges camera rays see:
    their signed distance in the image and the radiance either side), shadow_edges.py (hard shadows' edges:
    their signed distance in the image and one light's term either side), aov.py (what a first hit records besides
    colour), clip.py and raster.py (the Z-buffer: Fragments), hybrid.py (where the Z-buffer's first hit is
    the tracer's), mirror.py (a reflection ray's first hit from a planar mirror's virtual camera),
    zbuffer_shade.py.
"""

from .._warp import init_warp, wp
from .aov import aov_buffers, aov_bytes, aov_sums, empty_aov_buffers
from .camera import CameraData, camera_data, camera_ray, raster_camera, sample_offset
from .clip import CLIP_SCALE
from .dielectric import beer, beer_forever, fresnel_dielectric, refract
from .grad import (MAX_GRAD_LIGHTS, TEXTURE_CLAMP, TEXTURE_MIRROR, TEXTURE_WRAP, area_replay, area_sample_term, bilinear,
                   camera_direction, camera_rays, corner_angle, light_factor, make_area_combine, make_grad_shade_kernel, sample_mean,
                   smooth_vertex_normals, spot_cone, texture_factor, vertex_normal_sums)
from .grad_tree import make_tree_record_kernel, make_tree_replay_kernel, tree_area_combine, tree_camera_rays
from .grad import POSE_TAYLOR, posed_point, posed_points, rodrigues_coefficients, translate_samples, vertex_colour
from .hybrid import MARGIN_PX, uncertain, uncertain_np
from .interaction import OFFSET_SCALE, make_surface, offset_ray_origin, reflect
from .mirror import MARGIN_PX as MIRROR_MARGIN_PX, MAX_BOUNCES, Mirrors, gather_kernel, mirror_chain, mirror_hit, probe_kernel, total_kernel
from .raster import Fragments, count_kernel, fill_kernel, project_kernel, raster_kernel, raster_pixel_kernel
from .shading import phong_diffuse, phong_specular
from .shadow import grid_occluded
from .trace import MAX_TREE_DEPTH, make_trace_kernel, stack_size, tile_order_pixel
from .triangle import query_normal, triangle, unit_normal, woop_hit
from .zbuffer_shade import make_shade_kernel

# What image/ launches and reads, and what tests and benchmarks compose into kernels of their own.
__all__ = ["CLIP_SCALE", "CameraData", "Fragments", "MARGIN_PX", "MAX_GRAD_LIGHTS", "TEXTURE_CLAMP", "TEXTURE_MIRROR", "TEXTURE_WRAP", "bilinear",
           "area_replay", "area_sample_term", "camera_direction", "camera_rays", "corner_angle", "smooth_vertex_normals", "vertex_normal_sums", "make_area_combine",
           "make_grad_shade_kernel", "make_tree_record_kernel", "make_tree_replay_kernel", "tree_area_combine", "tree_camera_rays", "MAX_BOUNCES", "MAX_TREE_DEPTH", "MIRROR_MARGIN_PX",
           "Mirrors", "OFFSET_SCALE", "aov_buffers", "aov_bytes", "aov_sums", "camera_data", "camera_ray",
           "beer", "beer_forever", "count_kernel", "empty_aov_buffers", "fill_kernel", "fresnel_dielectric", "gather_kernel", "grid_occluded",
           "init_warp", "light_factor", "make_shade_kernel", "make_surface", "make_trace_kernel", "mirror_chain", "mirror_hit",
           "offset_ray_origin", "phong_diffuse", "phong_specular", "probe_kernel", "project_kernel", "total_kernel", "query_normal",
           "raster_camera", "raster_kernel", "raster_pixel_kernel", "reflect", "refract", "sample_mean", "sample_offset", "spot_cone", "stack_size", "texture_factor", "tile_order_pixel",
           "triangle", "uncertain", "uncertain_np", "unit_normal", "woop_hit", "wp"]
__all__ += ["translate_samples", "vertex_colour"]  # the gradient's vertex colours and area lights' centres
__all__ += ["POSE_TAYLOR", "posed_point", "posed_points", "rodrigues_coefficients"]  # and objects' poses
from .record import NO_RAY, GradRecord, empty_record  # noqa: E402 (what a grad=True frame's trace writes)

__all__ += ["NO_RAY", "GradRecord", "empty_record"]
from .edges import edge_distance, edge_distances, make_edge_sides_kernel  # noqa: E402 (backward(edges=True))

__all__ += ["edge_distance", "edge_distances", "make_edge_sides_kernel"]
from .edges import plane_distance  # noqa: E402
from .shadow_edges import (SOURCE_LIGHT, SOURCE_SAMPLE, make_light_sides_kernel, shadow_edge_distances,  # noqa: E402
                           shadow_plane)

__all__ += ["plane_distance", "SOURCE_LIGHT", "SOURCE_SAMPLE", "make_light_sides_kernel", "shadow_edge_distances",
            "shadow_plane"]  # and hard shadows' edges
