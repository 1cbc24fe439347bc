"""Scene -> what the kernels read: one triangle set in float32 with its material, texture and light
tables (scene_data.py), the BVH over padded bounds (bvh.py), the shadow rays' light-space grid
(shadow_grid.py) and the scene seen through planar mirrors (planar.py)."""

from .bvh import BOUNDS_PAD, EYE_REACH, build_mesh, eye_reach, frame_origin, objects_center, padded_bounds
from .planar import MAX_GROUPS, MirroredGeometry, mirrored_geometry, planar_groups
from .scene_data import CHECKER, LIGHT_DIRECTIONAL, LIGHT_POINT, LIGHT_SPOT, Geometry, LightShape, SceneData, TextureSlot
from .shadow_grid import GridEntry, ShadowGrid, ShadowGridBuild, cells_for, empty_grid, kept_shadow_grid, shadow_grid

__all__ = ["BOUNDS_PAD", "CHECKER", "EYE_REACH", "LIGHT_DIRECTIONAL", "LIGHT_POINT", "LIGHT_SPOT", "LightShape",
           "MAX_GROUPS", "Geometry", "GridEntry", "MirroredGeometry", "SceneData",
           "ShadowGrid", "ShadowGridBuild", "TextureSlot", "build_mesh", "cells_for", "empty_grid", "eye_reach", "frame_origin",
           "kept_shadow_grid", "mirrored_geometry", "objects_center", "padded_bounds", "planar_groups", "shadow_grid"]
