"""Scene -> what the kernels read: one triangle set in camera-relative float32 with its material,
texture and light tables (scene_data.py), and the BVH over it, built from padded bounds (bvh.py)."""

from .bvh import BOUNDS_PAD, build_mesh, padded_bounds
from .scene_data import CHECKER, Geometry, SceneData, TextureSlot

__all__ = ["BOUNDS_PAD", "CHECKER", "Geometry", "SceneData", "TextureSlot", "build_mesh", "padded_bounds"]
