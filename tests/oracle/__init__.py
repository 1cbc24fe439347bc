"""The tests' independent expected values: each closed form written once, in float64, from the seed's
and the textbooks' formulas. It imports nothing from warprt: it reads a Camera, Material, Light or
Scene by its fields, and never calls warprt's geometry or shading.

    camera.py (the seed's pinhole rays) -> geometry.py (ray-triangle, ray-plane, ray-sphere, normals),
    transform.py (the scene file's rotate, an object's pose and its Jacobian), shading.py (Phong), optics.py (Fresnel, Snell, the slab's
    series, Beer), shadow.py (a point's hard shadow on a plane, its mirror image, its image) -> whitted.py (brute-force tracers,
    glass's ray tree included)
"""

from .camera import Pinhole, camera_rays, pinhole, pixel_directions, ray_directions
from .geometry import (TriangleHit, face_normals, nearest_triangle, ray_plane, ray_sphere_distance, ray_triangle,
                       vertex_normals, winding_number)
from .shadow import image_point, line_distance, mirror_point, shadow_point
from .shading import TERMS, light_direction, light_intensity, light_source, phong, phong_terms, spot_profile
from .transform import axis_rotation, cross_matrix, pose_gradients, pose_jacobian, posed, rotation, rotation_vector
from .whitted import (MITSUBA_RAY_EPSILON, MITSUBA_SHADOW_EPSILON, OFFSET_SWEEP, Branch, PixelTrace, Whitted,
                      shade_triangles, texture_value)

__all__ = ["Branch", "MITSUBA_RAY_EPSILON", "MITSUBA_SHADOW_EPSILON", "OFFSET_SWEEP", "Pinhole", "PixelTrace", "TERMS",
           "TriangleHit", "Whitted", "axis_rotation", "camera_rays", "face_normals", "light_direction", "light_intensity",
           "light_source",
           "nearest_triangle", "phong", "phong_terms", "pinhole", "pixel_directions", "ray_directions", "ray_plane",
           "ray_sphere_distance", "ray_triangle", "rotation", "shade_triangles", "spot_profile", "texture_value", "vertex_normals",
           "winding_number"]
__all__ += ["cross_matrix", "pose_gradients", "pose_jacobian", "posed", "rotation_vector"]
__all__ += ["image_point", "line_distance", "mirror_point", "shadow_point"]
