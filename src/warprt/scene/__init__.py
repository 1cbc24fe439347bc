"""file -> Scene: the scene model (float64, validated, no Warp), its readers and what derives from it
alone (the camera basis, vertex normals, the effect set).

    model.py (dataclasses) <- validate.py <- meshio.py (with dielectric_formats.py), shapes.py, normals.py
    <- reader.py (TOML) <- autoframe.py (a bare mesh) <- load.py (load_scene, overrides); effects.py,
    camera.py and dielectric.py (closed meshes, the eye's medium) beside them.
"""

from ..memo import ObjectCache
from . import shapes
from .camera import CameraBasis, camera_basis, pixel_ray_directions
from .dielectric import eye_medium, open_edges, signed_volume, warn_unclosed, winding_number
from .dielectric_formats import DEFAULT_IOR, dielectric_from_gltf, dielectric_from_mtl, dielectric_from_usd
from .effects import EFFECTS, EffectSet, resolve_effects, scene_effects, zbuffer_effects
from .load import apply_overrides, default_scene_path, load_scene
from .meshio import FORMATS as MESH_FORMATS, MeshFile, fan_triangulate, load_mesh, read_mesh_file
from .model import DEFAULT_MATERIAL, Camera, Light, Material, RenderSettings, Scene, SceneObject
from .normals import vertex_normals
from .reader import rotation, scene_from_dict
from .validate import MAX_IMAGE_SIDE, MAX_REACH, check_setting, validate_camera, validate_scene

__all__ = ["CameraBasis", "Camera", "DEFAULT_IOR", "DEFAULT_MATERIAL", "EFFECTS", "EffectSet", "Light", "MAX_IMAGE_SIDE",
           "MAX_REACH", "MESH_FORMATS", "Material", "MeshFile", "ObjectCache", "RenderSettings", "Scene", "SceneObject",
           "apply_overrides", "camera_basis", "check_setting", "default_scene_path", "dielectric_from_gltf",
           "dielectric_from_mtl", "dielectric_from_usd", "eye_medium", "fan_triangulate", "load_mesh", "load_scene",
           "open_edges", "pixel_ray_directions", "read_mesh_file", "resolve_effects", "rotation", "scene_effects",
           "scene_from_dict", "shapes", "signed_volume", "validate_camera", "validate_scene", "vertex_normals",
           "warn_unclosed", "winding_number", "zbuffer_effects"]
