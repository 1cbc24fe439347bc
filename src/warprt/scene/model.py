"""The scene: dataclasses that mirror the TOML file one to one. Everything is float64 here;
geometry becomes float32 only when it is handed to the BVH (warprt.geometry)."""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np


@dataclass(frozen=True)
class Camera:
    """The seed's pinhole camera: eye, center, up, fovy (degrees), near (d_f), image size."""

    eye: tuple = (0.0, 1.5, 5.0)
    center: tuple = (0.0, 0.8, 0.0)
    up: tuple = (0.0, 1.0, 0.0)
    fovy: float = 45.0
    near: float = 1.0
    width: int = 640
    height: int = 480


@dataclass(frozen=True)
class RenderSettings:
    ambient: tuple = (0.1, 0.1, 0.1)  # C_amb
    background: tuple = (0.0, 0.0, 0.0)
    max_depth: int = 3  # ray levels: 1 = primary only
    shadows: bool = True
    spp: int = 1  # k*k stratified samples per pixel
    effects: tuple | None = None  # None: every effect the scene calls for


@dataclass(frozen=True)
class Light:
    """A point light: position and colour C_l."""

    position: tuple
    color: tuple = (1.0, 1.0, 1.0)


@dataclass(frozen=True)
class Material:
    """Phong coefficients ka, kd, ks, the exponent n (shininess) and the mirror weight k_r."""

    kd: tuple = (0.7, 0.7, 0.7)
    ka: tuple | None = None  # None: the same as kd
    ks: tuple = (0.0, 0.0, 0.0)
    shininess: float = 32.0
    reflectivity: tuple = (0.0, 0.0, 0.0)  # k_r

    def __post_init__(self):
        if self.ka is None:
            object.__setattr__(self, "ka", self.kd)


@dataclass
class SceneObject:
    """One object: its triangles in world space (float64) and the name of its material."""

    name: str
    vertices: np.ndarray  # (N, 3) float64, world space
    faces: np.ndarray  # (M, 3) int64
    material: str
    smooth: bool = False
    # Vertex normals (N, 3) when the object is part of a larger smooth mesh (a file split by
    # material): computed over the whole mesh, so the split leaves no crease.
    normals: np.ndarray | None = None


@dataclass
class Scene:
    camera: Camera
    render: RenderSettings
    lights: list[Light]
    materials: dict[str, Material]
    objects: list[SceneObject]
    source: str = "<scene>"
    load_seconds: float | None = None  # time load_scene spent reading and validating
    files: tuple = ()  # the files it was read from: the scene file, then the mesh files it names

    @property
    def triangle_count(self) -> int:
        return int(sum(len(o.faces) for o in self.objects))

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        v = np.concatenate([o.vertices for o in self.objects]) if self.objects else np.zeros((1, 3))
        return v.min(0), v.max(0)

    def with_camera(self, **kw) -> "Scene":
        return replace(self, camera=replace(self.camera, **kw))

    def with_render(self, **kw) -> "Scene":
        return replace(self, render=replace(self.render, **kw))


DEFAULT_MATERIAL = Material(kd=(0.7, 0.7, 0.7), ks=(0.3, 0.3, 0.3), shininess=32.0)
