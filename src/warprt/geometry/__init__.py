"""Scene -> what the kernels read: one triangle set in float32 with its material, texture and light
tables (scene_data.py), the BVH over padded bounds (bvh.py), the shadow rays' light-space grid
(shadow_grid.py) and the scene seen through planar mirrors (planar.py)."""

from .bvh import build_mesh, frame_origin, objects_center
from .planar import MAX_GROUPS, mirrored_geometry, planar_groups
from .scene_data import (AreaLights, CHECKER, Environment, IMAGE, LIGHT_DIRECTIONAL, LIGHT_POINT, LIGHT_SPOT, TEXTURE_CLAMP,
                         TEXTURE_MIRROR, TEXTURE_WRAP, UNTEXTURED, Geometry, LightShape, SceneData, TextureSlot, light_shape,
                         light_strata, texel_array, texture_slots)
from .shadow_grid import ShadowGridBuild, cells_for, kept_shadow_grid, shadow_grid

__all__ = ["AreaLights", "Environment", "CHECKER", "IMAGE", "TEXTURE_CLAMP", "TEXTURE_MIRROR", "TEXTURE_WRAP", "UNTEXTURED",
           "texel_array", "texture_slots", "LIGHT_DIRECTIONAL", "LIGHT_POINT", "LIGHT_SPOT", "LightShape", "MAX_GROUPS", "Geometry",
           "SceneData", "ShadowGridBuild", "TextureSlot", "build_mesh", "cells_for", "frame_origin", "kept_shadow_grid",
           "light_shape", "light_strata", "mirrored_geometry", "objects_center", "planar_groups", "shadow_grid"]
