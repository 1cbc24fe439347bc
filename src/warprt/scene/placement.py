"""Where an object's triangles land in the world, and how they are shaded: the file's up axis turned to +y,
then scale, rotate, translate; the winding kept outward under a mirroring scale, the normals carried along.
One module for the scene file's objects, the mesh files they name and SceneObject's constructors."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import show
from . import shapes
from .normals import Shading, resolve_normals
from .toml_fields import TableReader

UP_AXES = ("x", "y", "z", "-x", "-y", "-z")

_UP_TO_Y = {
    "y": np.eye(3),
    "-y": np.array([[1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, -1.0]]),  # 180 degrees about x
    "z": np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]]),  # -90 about x: z -> y, y -> -z
    "-z": np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]]),  # +90 about x
    "x": np.array([[0.0, 1.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]),  # +90 about z: x -> y, y -> -x
    "-x": np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]),  # -90 about z
}


def up_rotation(axis: str) -> np.ndarray:
    """The rotation (det +1) that turns a file's up direction ("x", "-z", ...) to +y, warprt's up."""
    return _UP_TO_Y[axis.lower()]


def rotation(degrees) -> np.ndarray:
    """Rotation about x, then y, then z (R = Rz Ry Rx), angles in degrees."""
    ax, ay, az = np.radians(degrees)
    cx, sx, cy, sy, cz, sz = np.cos(ax), np.sin(ax), np.cos(ay), np.sin(ay), np.cos(az), np.sin(az)
    rx = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
    ry = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
    rz = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]])
    return rz @ ry @ rx


def euler_xyz(r: np.ndarray) -> tuple:
    """The angles (degrees) about x, y and z whose rotation (rotation(): Rz Ry Rx) is ``r``."""
    ay = math.asin(max(-1.0, min(1.0, -r[2, 0])))
    if abs(r[2, 0]) < 1.0 - 1e-12:
        ax, az = math.atan2(r[2, 1], r[2, 2]), math.atan2(r[1, 0], r[0, 0])
    else:  # gimbal lock: x and z turn about the same axis
        ax, az = 0.0, math.atan2(-r[0, 1], r[1, 1])
    return tuple(math.degrees(a) for a in (ax, ay, az))


def nearest_rotation(m: np.ndarray) -> tuple[np.ndarray, bool]:
    """The rotation (det +1) nearest the 3 x 3 ``m`` (its polar factor, a reflection's last axis turned
    back), and whether ``m`` was that rotation already (to 1e-6): an environment's to_world may turn it,
    nothing more."""
    u, _, vt = np.linalg.svd(m)
    r = u @ vt
    exact = bool(np.abs(r - m).max() <= 1e-6 and np.linalg.det(r) > 0)
    return (r if np.linalg.det(r) > 0 else u @ np.diag([1.0, 1.0, -1.0]) @ vt), exact


class PlacementOverflow(OverflowError):
    """Placed vertices beyond float64; the caller names the field (a file's objects[i].scale)."""


@dataclass(frozen=True)
class Placement:
    """An object's placement, as its [[objects]] table says it: world = R (s * (U v)) + t, with U the turn
    of its ``up`` axis to +y, s = ``scale``, R = rotation(``rotate``), t = ``translate``."""

    scale: tuple = (1.0, 1.0, 1.0)
    rotate: tuple = (0.0, 0.0, 0.0)
    translate: tuple = (0.0, 0.0, 0.0)
    up: str = "y"

    @property
    def linear(self) -> np.ndarray:
        """R diag(s) U, the part that acts on directions."""
        return rotation(self.rotate) @ np.diag(self.scale) @ up_rotation(self.up)

    @property
    def mirrored(self) -> bool:
        """Whether the placement turns space inside out (an odd number of negative scale factors): the
        sign of det(linear), read from the factors so that no over- or underflow of the product decides it."""
        return bool(np.prod(np.sign(self.scale)) < 0)

    def points(self, vertices: np.ndarray) -> np.ndarray:
        v = vertices if self.up == "y" else vertices @ up_rotation(self.up).T
        scale = np.asarray(self.scale)
        with np.errstate(over="ignore", invalid="ignore"):  # an absurd scale is reported here, once
            world = (v * scale) @ rotation(self.rotate).T + np.asarray(self.translate)
        if not np.all(np.isfinite(world)):
            raise PlacementOverflow(f"scale [{', '.join(f'{x:g}' for x in scale)}], rotate and translate take the mesh "
                                    "beyond the range of float64")
        return np.ascontiguousarray(world, np.float64)

    def winding(self, faces: np.ndarray) -> np.ndarray:
        """The faces, reversed under a mirroring placement so that they stay counter-clockwise from outside."""
        return faces[:, ::-1] if self.mirrored else faces

    def corner_normals(self, normals: np.ndarray) -> np.ndarray:
        """Normals per corner (M, 3, 3) placed: reordered as winding() reorders corners, mapped by the
        inverse transpose (row vectors: n' = n L^-1)."""
        with np.errstate(all="ignore"):  # an absurd scale is reported once, by points()
            normal_map = np.linalg.inv(self.linear)
        return (normals[:, ::-1] if self.mirrored else normals) @ normal_map


def read_placement(r: TableReader, default_up: str = "y") -> Placement:
    """An object table's scale, rotate, translate and up (``default_up``: the file's own up axis)."""
    scale = r.vector("scale", 1.0, allow_scalar=True)
    if 0.0 in scale:
        r.fail("scale", f"expected non-zero scale factors, got {list(scale)}")
    rotate = r.vector("rotate", (0.0, 0.0, 0.0))
    translate = r.vector("translate", (0.0, 0.0, 0.0))
    up = r.table.get("up", default_up)
    if not isinstance(up, str) or up.lower() not in UP_AXES:
        r.fail("up", f"expected one of {', '.join(repr(a) for a in UP_AXES)}, got {show(up)}")
    return Placement(scale, rotate, translate, up.lower())


def read_smooth(r: TableReader, key: str = "smooth", default=False):
    """true, false, "auto" or a crease angle in degrees (0 to 180): normals.resolve_normals' choice."""
    v = r.table.get(key, default)
    if isinstance(v, bool) or v == "auto":
        return v
    if isinstance(v, (int, float)):
        return r.number(key, lo=0.0, hi=180.0)
    r.fail(key, f"expected true, false, \"auto\" or a crease angle in degrees, got {show(v)}")


def place_triangles(vertices, faces, smooth, placement: Placement | None = None, corner_normals=None,
                    smoothing_group=None, **kw) -> tuple[np.ndarray, Shading]:
    """The triangles in the world (``placement`` None: as given, untouched) and their Shading
    (normals.resolve_normals, with ``corner_normals``, the triangles' own, placed alike)."""
    if placement is not None:
        vertices = placement.points(vertices)
        faces = placement.winding(faces)
        if corner_normals is not None:
            corner_normals = placement.corner_normals(corner_normals)
    faces = np.ascontiguousarray(faces, np.int64)
    return vertices, resolve_normals(vertices, faces, smooth, corner_normals, smoothing_group, **kw)


def shape_fields(r: TableReader, textured: bool, normals: np.ndarray | None = None) -> dict:
    """SceneObject's fields but its material, for the table of a built-in shape (``shape = "..."``):
    built (shapes.read_shape; with texture coordinates where ``textured`` and the shape has them),
    placed and shaded as the table says; ``normals`` per vertex, from Python (used where smooth = "auto")."""
    kind, vertices, faces, uv, colors = shapes.read_shape(r, textured)
    placement = read_placement(r)
    name, smooth = r.string("name", kind), read_smooth(r)
    if len(faces) == 0:
        r.fail("shape", "the mesh has no triangles")
    if faces.min() < 0 or faces.max() >= len(vertices):
        r.fail("faces", f"vertex index out of range [0, {len(vertices) - 1}]")
    if normals is not None and len(normals) != len(vertices):
        r.fail("normals", f"expected one per vertex ({len(vertices)}), got {len(normals)}")
    try:
        world, shading = place_triangles(vertices, faces, smooth, placement,
                                         None if normals is None else normals[faces])
    except PlacementOverflow as e:
        r.fail("scale", str(e))
    return dict(name=name, vertices=shading.take(world), faces=shading.faces, smooth=shading.smooth,
                normals=shading.normals, uv=shading.take(uv), colors=shading.take(colors))
