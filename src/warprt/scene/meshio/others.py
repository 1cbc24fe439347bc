"""STL, OFF and any other format trimesh reads: the triangles of every geometry node in the file's
world space. These formats carry no uv, colours or normals that are read here."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ...errors import SceneError, one_line
from . import MeshFile, MeshPart


def read_with_trimesh(path: Path) -> MeshFile:
    import trimesh

    src, ext = str(path), path.suffix.lower()
    try:
        # process=False keeps the file's vertices as they are: no merging, no removal of faces.
        loaded = trimesh.load(src, process=False)
    except Exception as e:
        raise SceneError(src, None, f"cannot read {ext[1:].upper()} file: {one_line(e, type(e).__name__)}") from None
    if isinstance(loaded, trimesh.Trimesh):
        loaded = trimesh.Scene(loaded)
    if not isinstance(loaded, trimesh.Scene):
        raise SceneError(src, None, "the mesh has no triangles")
    parts = []
    for node in loaded.graph.nodes_geometry:
        transform, geom_name = loaded.graph[node]
        g = loaded.geometry[geom_name]
        if not isinstance(g, trimesh.Trimesh) or len(g.faces) == 0:
            continue
        t = np.asarray(transform, np.float64)
        vertices = np.asarray(g.vertices, np.float64) @ t[:3, :3].T + t[:3, 3]
        faces = np.asarray(g.faces, np.int64).reshape(-1, 3)
        if np.linalg.det(t[:3, :3]) < 0:  # a mirroring node transform turns the winding over
            faces = faces[:, ::-1]
        parts.append(MeshPart(str(node), vertices, np.ascontiguousarray(faces), np.full(len(faces), -1, np.int64)))
    return MeshFile(path, parts)
