"""A scene for a bare mesh file: the mesh, a default material, two lights and a camera that frames it."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from .errors import SceneError
from .scene import Camera, Light, Material, RenderSettings, Scene, SceneObject


def scene_for_mesh(path: Path, width: int = 640, height: int = 480) -> Scene:
    from .scene import _load_mesh_file

    vertices, faces = _load_mesh_file(str(path), "mesh", Path(path))
    lo, hi = vertices.min(0), vertices.max(0)
    center = 0.5 * (lo + hi)
    radius = 0.5 * float(np.linalg.norm(hi - lo))
    if not radius > 0.0:
        raise SceneError(str(path), "mesh", "the mesh has zero extent")
    fovy = 40.0
    # Distance at which the bounding sphere fills the vertical field of view, with a margin.
    dist = 1.1 * radius / math.sin(math.radians(fovy) / 2)
    view = np.array([0.5, 0.35, 1.0])
    view /= np.linalg.norm(view)
    eye = center + dist * view
    camera = Camera(eye=tuple(eye), center=tuple(center), up=(0.0, 1.0, 0.0), fovy=fovy,
                    near=1.0, width=width, height=height)
    lights = [
        Light(position=tuple(center + radius * np.array([4.0, 6.0, 4.0])), color=(0.8, 0.8, 0.8)),
        Light(position=tuple(center + radius * np.array([-5.0, 3.0, 2.0])), color=(0.3, 0.3, 0.35)),
    ]
    material = Material(kd=(0.75, 0.72, 0.68), ka=(0.75, 0.72, 0.68), ks=(0.25, 0.25, 0.25), shininess=48.0)
    obj = SceneObject(name=Path(path).stem, vertices=vertices, faces=faces, material="mesh", smooth=True)
    return Scene(camera, RenderSettings(ambient=(0.15, 0.15, 0.15), max_depth=1), lights,
                 {"mesh": material}, [obj], str(path))
