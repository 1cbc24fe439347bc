"""file -> Scene: the scene model (float64, validated, no Warp), its readers and what derives from it
alone (the camera basis, vertex normals, the effect set).

    texture.py (images, checker) <- model.py (dataclasses) <- validate.py <- normals.py, shapes.py
    <- meshio/ (one reader a format) <- reader.py (TOML) <- autoframe.py (a bare mesh) <- load.py
    (load_scene, overrides, with_overrides); effects.py, camera.py beside them.
"""

from ..memo import ObjectCache
from . import shapes
from .camera import CameraBasis, camera_basis, pixel_ray_directions
from .effects import EFFECTS, EffectSet, resolve_effects, scene_effects, zbuffer_effects
from .load import apply_overrides, default_scene_path, load_scene, sets_in_place, with_overrides
from .meshio import FORMATS as MESH_FORMATS, MeshFile, fan_triangulate, load_mesh, read_mesh_file
from .model import DEFAULT_MATERIAL, Camera, Light, Material, RenderSettings, Scene, SceneObject
from .normals import AUTO_CREASE_DEGREES, corner_normals, resolve_normals, vertex_normals
from .reader import UP_AXES, rotation, scene_from_dict, up_rotation
from .texture import Texture, checker_texture, image_texture, srgb_to_linear
from .validate import MAX_IMAGE_SIDE, MAX_REACH, check_setting, validate_camera, validate_scene

__all__ = ["AUTO_CREASE_DEGREES", "Camera", "CameraBasis", "DEFAULT_MATERIAL", "EFFECTS", "EffectSet", "Light",
           "MAX_IMAGE_SIDE", "MAX_REACH", "MESH_FORMATS", "Material", "MeshFile", "ObjectCache", "RenderSettings",
           "Scene", "SceneObject", "Texture", "UP_AXES", "apply_overrides", "camera_basis", "check_setting",
           "checker_texture", "corner_normals", "default_scene_path", "fan_triangulate", "image_texture",
           "load_mesh", "load_scene", "pixel_ray_directions", "read_mesh_file", "resolve_effects", "resolve_normals",
           "rotation", "scene_effects", "scene_from_dict", "sets_in_place", "shapes", "srgb_to_linear",
           "up_rotation", "validate_camera", "validate_scene", "vertex_normals", "with_overrides", "zbuffer_effects"]
