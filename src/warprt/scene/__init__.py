"""file -> Scene: the scene model (float64, validated, no Warp), its readers and what derives from it
alone (the camera basis, vertex normals, the effect set).

    texture.py (images, checker) <- model.py (dataclasses) <- validate.py <- normals.py, shapes.py,
    dielectric.py (closed meshes, the eye's medium) <- meshio/ (one reader a format, with
    dielectric_formats.py) <- reader.py (TOML) <- autoframe.py (a bare mesh) <- load.py (load_scene,
    overrides, with_overrides); effects.py, camera.py beside them.
"""

from ..memo import ObjectCache
from . import shapes
from .camera import CameraBasis, camera_basis, pixel_ray_directions
from .dielectric import eye_medium, open_edges, signed_volume, warn_unclosed, winding_number
from .dielectric_formats import DEFAULT_IOR, dielectric_from_gltf, dielectric_from_mtl, dielectric_from_usd
from .effects import EFFECTS, EffectSet, resolve_effects, scene_effects, zbuffer_effects
from .load import apply_overrides, default_scene_path, load_scene, sets_in_place, with_overrides
from .meshio import FORMATS as MESH_FORMATS, MeshFile, fan_triangulate, load_mesh, read_mesh_file
from .mitsuba_xml import load_mitsuba_file, mitsuba_camera, read_mitsuba_xml, reads_mitsuba_shape
from .model import DEFAULT_MATERIAL, Camera, Light, Material, RenderSettings, Scene, SceneObject
from .normals import AUTO_CREASE_DEGREES, corner_normals, resolve_normals, vertex_normals
from .reader import UP_AXES, rotation, scene_from_dict, up_rotation
from .texture import Texture, checker_texture, image_texture, srgb_to_linear
from .validate import MAX_IMAGE_SIDE, MAX_REACH, check_setting, validate_camera, validate_scene

__all__ = ["apply_overrides", "AUTO_CREASE_DEGREES", "Camera", "camera_basis", "CameraBasis", "check_setting",
           "checker_texture", "corner_normals", "DEFAULT_IOR", "DEFAULT_MATERIAL", "default_scene_path",
           "dielectric_from_gltf", "dielectric_from_mtl", "dielectric_from_usd", "EFFECTS", "EffectSet",
           "eye_medium", "fan_triangulate", "image_texture", "Light", "load_mesh", "load_scene", "Material",
           "load_mitsuba_file", "MAX_IMAGE_SIDE", "MAX_REACH", "MESH_FORMATS", "MeshFile", "mitsuba_camera", "ObjectCache", "open_edges",
           "pixel_ray_directions", "read_mesh_file", "read_mitsuba_xml", "reads_mitsuba_shape", "RenderSettings", "resolve_effects", "resolve_normals",
           "rotation", "Scene", "scene_effects", "scene_from_dict", "SceneObject", "sets_in_place", "shapes",
           "signed_volume", "srgb_to_linear", "Texture", "UP_AXES", "up_rotation", "validate_camera",
           "validate_scene", "vertex_normals", "warn_unclosed", "winding_number", "with_overrides",
           "zbuffer_effects"]
