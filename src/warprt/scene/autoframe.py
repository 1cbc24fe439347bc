"""A scene for a bare mesh file: the mesh, a default material, two lights and a camera that frames it."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ..errors import SceneError
from .dielectric import warn_unclosed
from .meshio import read_mesh_file, split_by_material
from .model import Camera, Light, Material, RenderSettings, Scene


# The framing below is written for a y-up file; a z-up one (a USD stage may say so) turns it
# by +90 degrees about x, so that the camera's up is the file's up.
_TO_UP = {"Y": np.eye(3), "Z": np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])}


def scene_for_mesh(path: Path, width: int = 640, height: int = 480) -> Scene:
    mesh = read_mesh_file(path)
    vertices, faces, face_material, part_starts = mesh.concatenated()
    to_up = _TO_UP.get(mesh.up_axis, _TO_UP["Y"])
    lo, hi = vertices.min(0), vertices.max(0)
    center = 0.5 * (lo + hi)
    radius = 0.5 * float(np.linalg.norm(hi - lo))
    if not radius > 0.0:
        raise SceneError(str(path), "mesh", "the mesh has zero extent")
    fovy = 40.0
    # Distance at which the bounding sphere fills the vertical field of view, with a margin.
    dist = 1.1 * radius / math.sin(math.radians(fovy) / 2)
    view = to_up @ np.array([0.5, 0.35, 1.0])
    view /= np.linalg.norm(view)
    eye = center + dist * view
    camera = Camera(eye=_floats(eye), center=_floats(center), up=_floats(to_up @ [0.0, 1.0, 0.0]), fovy=fovy,
                    near=1.0, width=width, height=height)
    lights = [
        Light(position=_floats(center + radius * (to_up @ [4.0, 6.0, 4.0])), color=(0.8, 0.8, 0.8)),
        Light(position=_floats(center + radius * (to_up @ [-5.0, 3.0, 2.0])), color=(0.3, 0.3, 0.35)),
    ]
    materials = {"mesh": Material(kd=(0.75, 0.72, 0.68), ka=(0.75, 0.72, 0.68), ks=(0.25, 0.25, 0.25), shininess=48.0)}
    # The file's own materials where it has them; "mesh" for faces without one.
    objects = split_by_material(Path(path).stem, vertices, faces, face_material, mesh.materials, materials,
                                "mesh", True, part_starts)
    # Primary rays only, unless the file has mirrors (MTL illum 3): then two reflection levels; or
    # glass, whose ray tree needs at least two levels per crossing.
    mirrors = any(max(m.reflectivity) > 0 for _, m in mesh.materials)
    glass = any(m.dielectric for _, m in mesh.materials)
    scene = Scene(camera, RenderSettings(ambient=(0.15, 0.15, 0.15), max_depth=6 if glass else 3 if mirrors else 1),
                  lights, materials, objects, str(path))
    warn_unclosed(scene)
    return scene


def _floats(v) -> tuple:
    """Plain floats, as a scene file gives them (info prints them; NumPy scalars print noisily)."""
    return tuple(float(x) for x in v)
