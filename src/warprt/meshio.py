"""Mesh files in: whatever trimesh reads (OBJ, PLY, STL, OFF, glTF/GLB, ...), as float64 triangles."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import trimesh

from .errors import SceneError


def load_mesh(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """Vertices (N, 3) float64 and faces (M, 3) int64 of every triangle in the file, in the
    file's world space (a multi-mesh scene is flattened with its node transforms)."""
    path = Path(path)
    if not path.exists():
        raise FileNotFoundError(path)
    if path.is_dir():
        raise SceneError(str(path), None, "is a directory, not a mesh file")
    # process=False keeps the file's vertices as they are: no merging, no removal of degenerate faces.
    loaded = trimesh.load(str(path), process=False, force="mesh")
    if isinstance(loaded, trimesh.Scene):
        loaded = loaded.to_geometry()
    if not isinstance(loaded, trimesh.Trimesh):
        raise SceneError(str(path), None, f"holds no triangle mesh (found {type(loaded).__name__})")
    vertices = np.asarray(loaded.vertices, np.float64)
    faces = np.asarray(loaded.faces, np.int64).reshape(-1, 3)
    if len(faces) == 0:
        raise SceneError(str(path), None, "the mesh has no triangles")
    if not np.all(np.isfinite(vertices)):
        raise SceneError(str(path), None, "vertex coordinates contain NaN or Inf")
    return vertices, faces
