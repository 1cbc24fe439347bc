"""The scene flattened for the kernels: one triangle set in float32 relative to a frame origin, with a
per-triangle material slot, vertex normals for smooth objects, and per-frame material and light tables.

Coordinates are made relative to the frame origin (the eye of the first frame) in float64 before the
cast to float32, so a scene far from the world origin keeps the precision it has near it. Later
frames reuse the triangles and the BVH while their eye stays in the region the BVH's padding covers
(bvh.EYE_REACH); their camera rays start at the float32 eye - origin, exactly 0 for the first frame.
"""

from __future__ import annotations

import numpy as np
from .._warp import wp
from ..scene import vertex_normals
from .bvh import build_mesh, eye_reach
from .shadow_grid import ShadowGrid, empty_grid


@wp.struct
class SceneData:
    mesh: wp.uint64
    points: wp.array(dtype=wp.vec3)
    indices: wp.array(dtype=wp.int32)
    normals: wp.array(dtype=wp.vec3)  # per vertex; zero where the object is flat
    tri_material: wp.array(dtype=wp.int32)
    tri_smooth: wp.array(dtype=wp.int32)
    ka: wp.array(dtype=wp.vec3)
    kd: wp.array(dtype=wp.vec3)
    ks: wp.array(dtype=wp.vec3)
    kr: wp.array(dtype=wp.vec3)
    shininess: wp.array(dtype=float)
    light_pos: wp.array(dtype=wp.vec3)  # relative to the frame origin
    light_color: wp.array(dtype=wp.vec3)
    num_lights: int
    ambient: wp.vec3  # C_amb
    background: wp.vec3
    shadow_grid: ShadowGrid  # the light-space structure (shadow_grid.py), read where shadow rays use it


class Geometry:
    """Owns the device arrays and the BVH for one set of objects, in coordinates relative to
    ``origin`` (default: the scene's eye); ``scene_data(scene)`` gives the kernels a frame's view."""

    def __init__(self, scene, device="cpu", bvh_constructor: str = "sah", build_bvh: bool = True, origin=None):
        # build_bvh=False: the Z-buffer needs the triangles and tables but never a ray query, and
        # its timings must not pay for a BVH (about 1.5 s for a million triangles on the CPU).
        self.device = device
        self.origin = np.asarray(scene.camera.eye if origin is None else origin, np.float64)  # world position
        # A triangle's material is a slot: the objects' material names in order of first use, so the
        # triangle arrays depend on the objects alone and a frame with other materials only swaps tables.
        self.material_names = list(dict.fromkeys(obj.material for obj in scene.objects))
        verts, faces, mats, smooth, normals, owner = [], [], [], [], [], []
        base = 0
        for index, obj in enumerate(scene.objects):
            owner.append(np.full(len(obj.faces), index, np.int32))
            verts.append(obj.vertices - self.origin)
            faces.append(obj.faces + base)
            mats.append(np.full(len(obj.faces), self.material_names.index(obj.material), np.int32))
            smooth.append(np.full(len(obj.faces), int(obj.smooth), np.int32))
            if obj.smooth:
                given = getattr(obj, "normals", None)
                normals.append(given if given is not None else vertex_normals(obj.vertices, obj.faces))
            else:
                normals.append(np.zeros_like(obj.vertices))
            base += len(obj.vertices)
        if not verts:  # an empty scene still gets a (degenerate, never hit) mesh so kernels can run
            verts, faces = [np.zeros((3, 3))], [np.zeros((1, 3), np.int64)]
            mats, smooth, normals = [np.zeros(1, np.int32)], [np.zeros(1, np.int32)], [np.zeros((3, 3))]
            owner = [np.zeros(1, np.int32)]
            self.triangle_count = 0
        else:
            self.triangle_count = int(sum(len(f) for f in faces))
        self.points_np = np.ascontiguousarray(np.concatenate(verts), np.float32)
        self.indices_np = np.ascontiguousarray(np.concatenate(faces).reshape(-1), np.int32)
        self.tri_material_np = np.concatenate(mats)
        self.tri_smooth_np = np.concatenate(smooth)
        self.tri_object_np = np.concatenate(owner)  # the index of each triangle's object
        self.eye_reach = eye_reach(self.points_np)  # E: how far an eye may move and keep this BVH

        d = device
        if build_bvh:
            # Padded triangle boxes (bvh.py): rays through shared vertices and edges cannot leak.
            # The points array then also holds the boxes' corners, after the V real points.
            self.mesh, self.points, self.indices = build_mesh(self.points_np, self.indices_np, d, bvh_constructor,
                                                              eye=self.eye_reach)
        else:
            self.points = wp.array(self.points_np, dtype=wp.vec3, device=d)
            self.indices = wp.array(self.indices_np, dtype=wp.int32, device=d)
            self.mesh = None
        self.normals = wp.array(np.concatenate(normals).astype(np.float32), dtype=wp.vec3, device=d)
        self.tri_material = wp.array(self.tri_material_np, dtype=wp.int32, device=d)
        self.tri_smooth = wp.array(self.tri_smooth_np, dtype=wp.int32, device=d)
        self._tables = None
        self.data = self.scene_data(scene)  # the tables of the scene it was built for

    def eye_offset(self, eye) -> np.ndarray:
        """Where the camera rays of an eye at world position ``eye`` start: eye - origin, computed in
        float64 and rounded to float32 as the points were (exactly 0 at the origin)."""
        return (np.asarray(eye, np.float64) - self.origin).astype(np.float32)

    def covers(self, eye) -> bool:
        """Whether camera rays from ``eye`` (world) keep the BVH's guarantees: within eye_reach of the
        origin on every axis (bvh.py: the padding's slab-test argument)."""
        return bool(np.abs(np.asarray(eye, np.float64) - self.origin).max() <= self.eye_reach)

    def light_positions(self, scene) -> np.ndarray:
        """The kernels' light positions (L, 3): relative to the origin in float64, then float32."""
        return np.asarray([np.asarray(l.position, np.float64) - self.origin for l in scene.lights],
                          np.float32).reshape(-1, 3)

    def scene_data(self, scene, shadow_grid: ShadowGrid | None = None) -> SceneData:
        """The kernels' view of these triangles for a frame of ``scene``: its materials, lights,
        ambient and background as small new arrays where they changed, and the shadow rays' grid if
        one is given; the triangle arrays and the BVH are shared, never rebuilt."""
        m = [scene.materials[n] for n in self.material_names]
        key = (tuple(m), tuple(scene.lights), tuple(scene.render.ambient), tuple(scene.render.background),
               id(shadow_grid))
        if self._tables is not None and self._tables[0] == key:
            return self._tables[1]
        d, lights = self.device, scene.lights
        s = SceneData()
        s.mesh = self.mesh.id if self.mesh is not None else wp.uint64(0)
        s.points = self.points
        s.indices = self.indices
        s.normals = self.normals
        s.tri_material = self.tri_material
        s.tri_smooth = self.tri_smooth
        vec = lambda rows: wp.array(np.asarray(rows, np.float32).reshape(-1, 3), dtype=wp.vec3, device=d)
        s.ka = vec([x.ka for x in m] or [[0, 0, 0]])
        s.kd = vec([x.kd for x in m] or [[0, 0, 0]])
        s.ks = vec([x.ks for x in m] or [[0, 0, 0]])
        s.kr = vec([x.reflectivity for x in m] or [[0, 0, 0]])
        s.shininess = wp.array(np.asarray([x.shininess for x in m] or [0.0], np.float32), dtype=float, device=d)
        s.light_pos = vec(self.light_positions(scene) if lights else [[0, 0, 0]])
        s.light_color = vec([l.color for l in lights] or [[0, 0, 0]])
        s.num_lights = len(lights)
        s.ambient = wp.vec3(*scene.render.ambient)
        s.background = wp.vec3(*scene.render.background)
        if shadow_grid is None:
            self.__dict__.setdefault("_no_grid", empty_grid(d))
        s.shadow_grid = shadow_grid if shadow_grid is not None else self._no_grid
        self._tables = (key, s, shadow_grid)  # the grid kept alive while its id is in the key
        return s
