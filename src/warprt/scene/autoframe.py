"""A scene for a bare mesh file: the mesh with its own materials (a default one elsewhere), shaded
"auto", the file's lights (else two) and its first camera (else one that frames it for the final image
size, along the file's up axis)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ..diagnostics import warn
from ..errors import ArgumentError, SceneError
from .camera import aspect_note, find_camera
from .dielectric import warn_unclosed
from .meshio import file_objects, read_mesh_file, warn_if_tiny, warn_if_unmapped
from .model import Light, Material, RenderSettings, Scene
from .placement import UP_AXES, up_rotation
from .reader import read_camera

DEFAULT_SIZE = (640, 480)
DEFAULT_FOVY = 40.0
MARGIN = 1.1  # the bounding sphere fills the narrower field of view to 1 / MARGIN


def scene_for_mesh(path: Path, camera: dict | None = None, up: str | None = None, view=None) -> Scene:
    """The framed scene. ``camera``: the camera fields the user set (TOML values, checked here), the
    rest the file camera's or framed for them; ``up``: the file's up axis ("x", "-z", ...), else the one
    the file declares (USD's upAxis, glTF's y), else y; ``view``: which of the file's cameras (its name
    or index; None: the first, if it has any), or "auto" for the framing."""
    source = str(path)
    mesh = read_mesh_file(path)
    file_camera = None
    if view != "auto" and (mesh.cameras or view is not None):
        try:
            file_camera = find_camera(mesh.cameras, view)
        except LookupError as e:
            if view is None:
                raise SceneError(source, None, f"{e} (render with camera 'auto' to frame the mesh instead)") from None
            raise ArgumentError("load_scene", "camera", f"{source}: {e}") from None
    if up is not None and up.lower() not in UP_AXES:
        raise ArgumentError("load_scene", "up", f"expected one of {', '.join(UP_AXES)}, got '{up}'")
    axis = (up or mesh.up_axis or "y").lower()
    # The framing below is written for a y-up file: turned so that the camera's up is the file's up.
    to_up = up_rotation(axis).T
    materials = {"mesh": Material(kd=(0.75, 0.72, 0.68), ka=(0.75, 0.72, 0.68), ks=(0.25, 0.25, 0.25), shininess=48.0)}
    # The file's own materials where it has them; "mesh" for faces without one.
    objects = file_objects(Path(path).stem, mesh, materials, "mesh", "auto")
    vertices = np.concatenate([o.vertices for o in objects])
    warn_if_tiny(source, None, vertices)
    warn_if_unmapped(source, None, objects, materials)
    lo, hi = vertices.min(0), vertices.max(0)
    center = 0.5 * (lo + hi)
    radius = 0.5 * float(np.linalg.norm(hi - lo))
    if not radius > 0.0:
        raise SceneError(source, "mesh", "the mesh has zero extent")
    if file_camera is None:
        camera = read_camera(source, _framed(dict(camera or {}), center, radius, to_up))
    else:
        camera = read_camera(source, {**file_camera.fields(center), "width": DEFAULT_SIZE[0], "height": DEFAULT_SIZE[1],
                                      **(camera or {})})
        note = aspect_note(file_camera, camera.width, camera.height)
        if note:
            warn(source, None, note)
    lights = list(mesh.lights) or [
        Light(position=_floats(center + radius * (to_up @ [4.0, 6.0, 4.0])), color=(0.8, 0.8, 0.8)),
        Light(position=_floats(center + radius * (to_up @ [-5.0, 3.0, 2.0])), color=(0.3, 0.3, 0.35)),
    ]
    # Primary rays only, unless the file has mirrors (MTL illum 3): then two reflection levels; or
    # glass, whose ray tree needs at least two levels per crossing.
    mirrors = any(max(m.reflectivity) > 0 for _, m in mesh.materials)
    glass = any(m.dielectric for _, m in mesh.materials)
    scene = Scene(camera, RenderSettings(ambient=(0.15, 0.15, 0.15), max_depth=6 if glass else 3 if mirrors else 1),
                  lights, materials, objects, source, cameras=tuple(mesh.cameras))
    warn_unclosed(scene)
    return scene


def _framed(given: dict, center, radius: float, to_up) -> dict:
    """The camera table: the user's fields as given, the others chosen so that the mesh's bounding
    sphere fits both fields of view of the final image, seen from the front, a little above."""
    def number(key, default, ok):
        v = given.get(key, default)
        return v if isinstance(v, (int, float)) and not isinstance(v, bool) and ok(v) else default

    width = number("width", DEFAULT_SIZE[0], lambda v: v >= 1)
    height = number("height", DEFAULT_SIZE[1], lambda v: v >= 1)
    fovy = number("fovy", DEFAULT_FOVY, lambda v: 0 < v < 180)
    half_v = math.radians(fovy) / 2
    half_h = math.atan(math.tan(half_v) * width / height)
    dist = MARGIN * radius / math.sin(min(half_v, half_h))
    view = to_up @ np.array([0.5, 0.35, 1.0])
    view /= np.linalg.norm(view)
    out = {"center": _floats(center), "up": _floats(to_up @ [0.0, 1.0, 0.0]), "fovy": DEFAULT_FOVY,
           "near": 1.0, "width": DEFAULT_SIZE[0], "height": DEFAULT_SIZE[1]}
    if "center" in given:
        try:
            center = np.asarray(given["center"], np.float64).reshape(3)
        except (TypeError, ValueError):
            pass  # read_camera reports it
    out["eye"] = _floats(center + dist * view)
    out.update(given)
    return {k: list(v) if isinstance(v, tuple) else v for k, v in out.items()}


def _floats(v) -> tuple:
    """Plain floats, as a scene file gives them (info prints them; NumPy scalars print noisily)."""
    return tuple(float(x) for x in v)
