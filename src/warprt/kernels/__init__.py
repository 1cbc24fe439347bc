"""The Warp functions and kernels, one concept a file:

    camera.py (the tracer's and the rasterizer's cameras, sample positions), triangle.py (a face's
    vertices, normal and Woop test), interaction.py (the hit record, its error bound, the ray offset,
    reflect, a mirror's bounce), texture.py (a material colour's texture at a hit), shading.py (Phong: how a
    light arrives and what it adds), shadow.py (whether a shadow ray is blocked: the BVH's any-hit query or the
    light-space grid), dielectric.py (Fresnel, Snell, Beer), trace.py (the Whitted kernel and its ray tree),
    record.py (what a grad=True frame's trace writes for its derivative), replay.py (the derivative: the record
    replayed with the forward's functions on a wp.Tape, a launch a ray level), pose.py (an object's pose as the
    derivative moves it), vertex_normals.py (smooth normals from moving points), edges.py (the edges camera
    rays see: their signed distance in the image and the radiance either side), shadow_edges.py (hard shadows'
    edges: their signed distance in the image and one light's term either side), mirror_edges.py (the edges
    seen in planar mirrors: their signed distance in the image through the reflections), spot_edges.py (a spot's
    hard cone on a receiver: its signed distance in the image), glass_edges.py (the edges seen through glass: a
    camera ray's tree signature, and a boundary's function through the refractions), aov.py (what a first hit
    records besides colour), clip.py and raster.py (the Z-buffer: Fragments), hybrid.py (where the Z-buffer's
    first hit is the tracer's), mirror.py (a reflection ray's first hit from a planar mirror's virtual
    camera), zbuffer_shade.py.
"""

from .._warp import init_warp, wp
from .aov import aov_buffers, aov_bytes, aov_sums, empty_aov_buffers
from .camera import CameraData, camera_data, camera_of, camera_ray, image_plane_point, raster_camera, sample_offset
from .clip import CLIP_SCALE
from .dielectric import beer, beer_forever, fresnel_dielectric, refract
from .texture import bilinear, texel
from .pose import POSE_TAYLOR, posed_point, posed_points, rodrigues_coefficients
from .replay import (MAX_GRAD_LIGHTS, ReplayCamera, ReplayHits, ReplayRays, barycentrics_on, make_replay_level,
                     make_replay_combine, replay_area, sample_mean)
from .vertex_normals import corner_angle, smooth_vertex_normals, vertex_normal_sums
from .area_shape import ShapeLights, coordinate_system, shape_area, shape_axes, shape_points, shape_samples
from .hybrid import MARGIN_PX, uncertain, uncertain_np
from .interaction import OFFSET_SCALE, make_surface, offset_ray_origin, reflect
from .mirror import MARGIN_PX as MIRROR_MARGIN_PX, MAX_BOUNCES, Mirrors, gather_kernel, mirror_chain, mirror_hit, probe_kernel, total_kernel
from .raster import Fragments, count_kernel, fill_kernel, project_kernel, raster_kernel, raster_pixel_kernel
from .shading import (AreaTest, Coefficients, LightArrival, area_arrival, light_weight, make_coefficients,
                      make_light_arrival, make_light_terms, phong_diffuse, phong_specular, point_arrival, spot_profile)
from .interaction import Surface, mirror_ray, spawn_ray
from .dielectric import absorbed, absorbed_forever, dielectric_children
from .shadow import grid_occluded
from .trace import MAX_TREE_DEPTH, make_pixels_kernel, make_trace_kernel, stack_size, tile_order_pixel
from .triangle import query_normal, triangle, unit_normal, woop_hit
from .zbuffer_shade import make_shade_kernel

# What image/ launches and reads, and what tests and benchmarks compose into kernels of their own.
__all__ = ["CLIP_SCALE", "CameraData", "Fragments", "MARGIN_PX", "MAX_BOUNCES", "MAX_TREE_DEPTH", "MIRROR_MARGIN_PX",
           "Mirrors", "OFFSET_SCALE", "aov_buffers", "aov_bytes", "aov_sums", "beer", "beer_forever", "bilinear",
           "camera_data", "camera_of", "camera_ray", "count_kernel", "empty_aov_buffers", "fill_kernel",
           "fresnel_dielectric", "gather_kernel", "grid_occluded", "image_plane_point", "init_warp", "make_shade_kernel",
           "make_surface", "make_pixels_kernel", "make_trace_kernel", "mirror_chain", "mirror_hit", "offset_ray_origin", "phong_diffuse",
           "phong_specular", "probe_kernel", "project_kernel", "query_normal", "raster_camera", "raster_kernel",
           "raster_pixel_kernel", "reflect", "refract", "sample_offset", "stack_size", "texel", "tile_order_pixel",
           "total_kernel", "triangle", "uncertain", "uncertain_np", "unit_normal", "woop_hit", "wp"]
# The gradient: its replay, and what moves the points, normals and area lights' samples it reads.
__all__ += ["MAX_GRAD_LIGHTS", "ReplayCamera", "ReplayHits", "ReplayRays", "barycentrics_on", "make_replay_level",
            "replay_area", "make_replay_combine", "sample_mean", "corner_angle",
            "smooth_vertex_normals", "vertex_normal_sums", "POSE_TAYLOR", "posed_point", "posed_points",
            "rodrigues_coefficients", "ShapeLights", "coordinate_system", "shape_area", "shape_axes", "shape_points",
            "shape_samples"]
# The forward's functions the replay differentiates (tests gradcheck them one by one).
__all__ += ["AreaTest", "Coefficients", "LightArrival", "Surface", "absorbed", "absorbed_forever", "area_arrival",
            "dielectric_children", "light_weight", "make_coefficients", "make_light_arrival", "make_light_terms",
            "mirror_ray", "point_arrival", "spawn_ray", "spot_profile"]
from .record import NO_PARENT, NO_RAY, GradRecord, empty_record, make_entry  # noqa: E402 (what a grad=True frame's trace writes)

__all__ += ["NO_PARENT", "NO_RAY", "GradRecord", "empty_record", "make_entry"]
from .edges import checker_edge_distances, edge_distance, edge_distances, make_edge_sides_kernel  # noqa: E402 (backward(edges=True))

__all__ += ["checker_edge_distances", "edge_distance", "edge_distances", "make_edge_sides_kernel"]
from .edges import plane_distance  # noqa: E402
from .shadow_edges import (SOURCE_LIGHT, SOURCE_SAMPLE, make_light_sides_kernel, shadow_edge_distances,  # noqa: E402
                           shadow_plane)

__all__ += ["plane_distance", "SOURCE_LIGHT", "SOURCE_SAMPLE", "make_light_sides_kernel", "shadow_edge_distances",
            "shadow_plane"]  # and hard shadows' edges
from .edges import MirrorEnd, make_mirror_path  # noqa: E402
from .mirror_edges import (CONE, DIRECTIONAL_SHADOW, EDGE, POINT_SHADOW, make_mirror_faces_kernel,  # noqa: E402
                           make_mirrored_distances, mirrored_direction, mirrored_point)

__all__ += ["MirrorEnd", "make_mirror_path", "CONE", "DIRECTIONAL_SHADOW", "EDGE", "POINT_SHADOW", "make_mirror_faces_kernel",
            "make_mirrored_distances", "mirrored_direction", "mirrored_point"]  # and the edges seen in planar mirrors
from .spot_edges import cone_distance, spot_edge_distances  # noqa: E402 (a spot's hard cone: backward(edges=True))

__all__ += ["cone_distance", "spot_edge_distances"]

from .glass_edges import (CHECKER_LINE, DIRECTIONAL_WEDGE, FACE_EDGE, MIRRORED, POINT_WEDGE, REFLECTED,  # noqa: E402
                          SPOT_CONE, TRANSMITTED, bounce, make_tree_distances, make_tree_kernel)

__all__ += ["CHECKER_LINE", "DIRECTIONAL_WEDGE", "FACE_EDGE", "MIRRORED", "POINT_WEDGE", "REFLECTED", "SPOT_CONE",
            "TRANSMITTED", "bounce", "make_tree_distances", "make_tree_kernel"]  # and the edges seen through glass
