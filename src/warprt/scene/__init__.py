"""file -> Scene: the scene model (float64, validated, no Warp), its readers and what derives from it
alone (the camera basis, vertex normals, the effect set).

    toml_fields.py (TOML files, typed tables), texture.py (images, checker) <- shapes.py, normals.py <-
    placement.py (an object's triangles placed and shaded) <- model.py (dataclasses, SceneObject's
    constructors) <- validate.py <- dielectric.py (closed meshes, the eye's medium) <- meshio/ (one reader
    a format, with dielectric_formats.py) <- reader.py (TOML) <- autoframe.py (a bare mesh) <- load.py
    (load_scene, load_dict, overrides, with_overrides); effects.py, camera.py beside them.
"""

from ..memo import ObjectCache
from . import shapes
from .area import (EMITTER_MATERIAL, EMITTER_MATERIAL_NAME, SHAPE_KINDS, drawn_objects, emitter_area,
                   emitter_of_triangles, emitter_samples, local_coordinates, emitting_triangles, light_hull, sample_coordinates,
                   shape_frame, spread_strata)
from .camera import CameraBasis, camera_basis, pixel_ray_directions
from .dielectric import eye_medium, open_edges, signed_volume, winding_number
from .dielectric_formats import DEFAULT_IOR, dielectric_from_gltf, dielectric_from_mtl, dielectric_from_usd
from .environment import environment_samples, environment_texels, to_world
from .effects import EFFECTS, EffectSet, resolve_effects, scene_effects, switched_on, zbuffer_effects
from .load import input_kind, load_dict, load_scene, sets_in_place, with_overrides
from .meshio import read_mesh_file
from .mitsuba_xml import load_mitsuba_file, mitsuba_camera, read_mitsuba_xml, reads_mitsuba_light, reads_mitsuba_shape
from .model import AREA_ESTIMATORS, DEFAULT_MATERIAL, Camera, Light, Material, RenderSettings, Scene, SceneObject
from .normals import position_ids, vertex_normals
from .placement import rotation
from .reader import scene_from_dict
from .texture import Texture, srgb_to_linear
from .toml_fields import TableReader, did_you_mean, read_toml
from .validate import MAX_REACH, CheckedContent, check_setting, validate_camera, validate_scene, validate_view

__all__ = ["AREA_ESTIMATORS", "EMITTER_MATERIAL", "EMITTER_MATERIAL_NAME", "SHAPE_KINDS", "local_coordinates", "drawn_objects", "emitter_area", "emitter_of_triangles", "emitting_triangles", "light_hull", "spread_strata",
           "emitter_samples", "sample_coordinates", "shape_frame", "Camera", "camera_basis", "CameraBasis", "CheckedContent", "check_setting", "DEFAULT_IOR", "DEFAULT_MATERIAL",
           "did_you_mean", "dielectric_from_gltf", "dielectric_from_mtl", "dielectric_from_usd", "EFFECTS", "EffectSet",
           "environment_samples", "environment_texels", "eye_medium", "input_kind", "Light", "load_dict", "load_mitsuba_file", "load_scene", "Material", "MAX_REACH", "ObjectCache", "open_edges",
           "pixel_ray_directions", "position_ids", "mitsuba_camera", "read_mesh_file", "read_toml", "read_mitsuba_xml", "reads_mitsuba_light", "reads_mitsuba_shape", "RenderSettings", "resolve_effects", "rotation", "Scene",
           "scene_effects", "scene_from_dict", "switched_on", "SceneObject", "sets_in_place", "shapes", "signed_volume",
           "srgb_to_linear", "TableReader", "Texture", "to_world", "validate_camera", "validate_scene", "validate_view", "vertex_normals", "winding_number",
           "with_overrides", "zbuffer_effects"]
