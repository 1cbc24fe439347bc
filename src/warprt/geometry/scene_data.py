"""The scene flattened for the kernels: one triangle set in camera-relative float32, with a
per-triangle material index, vertex normals for smooth objects, uvs and colours per vertex where the
scene has them, material tables (Phong with its texture slots, and the dielectrics' ior, k_t and sigma),
the textures, the light table, and the medium the eye is in.

Coordinates are made relative to the eye in float64 before the cast to float32, so a scene far
from the origin keeps the precision it has near it (the camera ray origin is exactly 0).
"""

from __future__ import annotations

import numpy as np
from .._warp import wp
from ..scene import eye_medium, vertex_normals
from .bvh import build_mesh

CHECKER = -1  # TextureSlot.image: the procedural checker instead of an image


@wp.struct
class TextureSlot:
    """How one material colour (ka, kd or ks) is textured: ``image`` indexes SceneData.textures (0:
    untextured, the colour as it is; CHECKER: c0 and c1 on alternate unit squares), and the uv map
    u' = u_map . (u, v, 1), v' = v_map . (u, v, 1)."""

    image: int
    u_map: wp.vec3
    v_map: wp.vec3
    c0: wp.vec3
    c1: wp.vec3


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
    uvs: wp.array(dtype=wp.vec2)  # per vertex, where the scene has textures; (0, 0) for objects without
    colors: wp.array(dtype=wp.vec3)  # per vertex, where the scene has vertex colours; white elsewhere
    ka_map: wp.array(dtype=TextureSlot)  # per material
    kd_map: wp.array(dtype=TextureSlot)
    ks_map: wp.array(dtype=TextureSlot)
    textures: wp.array(dtype=wp.Texture2D)  # bilinear, repeat; slot 0 a 1x1 white one
    ior: wp.array(dtype=float)  # eta of a dielectric, 0 for an opaque material
    transmittance: wp.array(dtype=wp.vec3)  # k_t
    absorption: wp.array(dtype=wp.vec3)  # sigma per scene unit
    eye_medium: int  # the dielectric material holding the eye, -1: air
    light_pos: wp.array(dtype=wp.vec3)  # camera-relative
    light_color: wp.array(dtype=wp.vec3)
    num_lights: int
    ambient: wp.vec3  # C_amb
    background: wp.vec3


class Geometry:
    """Owns the device arrays and the BVH for one scene."""

    def __init__(self, scene, device="cpu", bvh_constructor: str = "sah", build_bvh: bool = True):
        # build_bvh=False: the Z-buffer needs the triangles and tables but never a ray query, and
        # its timings must not pay for a BVH (about 1.5 s for a million triangles on the CPU).
        self.device = device
        self.origin = np.asarray(scene.camera.eye, np.float64)  # world position of the eye
        names = list(scene.materials)
        verts, faces, mats, smooth, normals = [], [], [], [], []
        base = 0
        for obj in scene.objects:
            verts.append(obj.vertices - self.origin)
            faces.append(obj.faces + base)
            mats.append(np.full(len(obj.faces), names.index(obj.material), np.int32))
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
            self.triangle_count = 0
        else:
            self.triangle_count = int(sum(len(f) for f in faces))
        self.points_np = np.ascontiguousarray(np.concatenate(verts), np.float32)
        self.indices_np = np.ascontiguousarray(np.concatenate(faces).reshape(-1), np.int32)
        self.tri_material_np = np.concatenate(mats)
        self.material_names = names
        self.object_face_counts = [len(obj.faces) for obj in scene.objects]
        self.object_ids = None  # object_tables(), once built
        self._object_uv = [(len(obj.vertices), getattr(obj, "uv", None)) for obj in scene.objects]
        self.object_uv = None  # uv_tables(), once built

        d = device
        if build_bvh:
            # Padded triangle boxes (bvh.py): rays through shared vertices and edges cannot leak.
            # The points array then also holds the boxes' corners, after the V real points.
            self.mesh, self.points, self.indices = build_mesh(self.points_np, self.indices_np, d, bvh_constructor)
        else:
            self.points = wp.array(self.points_np, dtype=wp.vec3, device=d)
            self.indices = wp.array(self.indices_np, dtype=wp.int32, device=d)
            self.mesh = None

        m = [scene.materials[n] for n in names]
        lights = scene.lights
        s = SceneData()
        s.mesh = self.mesh.id if build_bvh else wp.uint64(0)
        s.points = self.points
        s.indices = self.indices
        s.normals = wp.array(np.concatenate(normals).astype(np.float32), dtype=wp.vec3, device=d)
        s.tri_material = wp.array(self.tri_material_np, dtype=wp.int32, device=d)
        s.tri_smooth = wp.array(np.concatenate(smooth), dtype=wp.int32, device=d)
        vec = lambda rows: wp.array(np.asarray(rows, np.float32).reshape(-1, 3), dtype=wp.vec3, device=d)
        s.ka = vec([x.ka for x in m])
        s.kd = vec([x.kd for x in m])
        s.ks = vec([x.ks for x in m])
        s.kr = vec([x.reflectivity for x in m])
        s.shininess = wp.array(np.asarray([x.shininess for x in m], np.float32), dtype=float, device=d)
        self._attributes(s, scene.objects, m, d)
        s.ior = wp.array(np.asarray([x.ior or 0.0 for x in m], np.float32), dtype=float, device=d)
        s.transmittance = vec([x.transmittance for x in m])
        s.absorption = vec([x.absorption for x in m])
        # Only the tracer follows rays into a medium (the Z-buffer's geometry has no BVH).
        medium = eye_medium(scene) if build_bvh and any(x.dielectric for x in m) else None
        s.eye_medium = names.index(medium) if medium is not None else -1
        s.light_pos = vec([np.asarray(l.position) - self.origin for l in lights] or [[0, 0, 0]])
        s.light_color = vec([l.color for l in lights] or [[0, 0, 0]])
        s.num_lights = len(lights)
        s.ambient = wp.vec3(*scene.render.ambient)
        s.background = wp.vec3(*scene.render.background)
        self.data = s

    def _attributes(self, s: SceneData, objects, materials, device):
        """uvs, colours, texture slots and textures; one-element stand-ins where the scene has none
        (the kernels read them only under the texture and vertex_color switches)."""
        textured = any(mat.textures for mat in materials)
        coloured = any(getattr(o, "colors", None) is not None for o in objects)
        uv = [o.uv if getattr(o, "uv", None) is not None else np.zeros((len(o.vertices), 2)) for o in objects]
        rgb = [o.colors if getattr(o, "colors", None) is not None else np.ones((len(o.vertices), 3)) for o in objects]
        s.uvs = wp.array(np.concatenate(uv).astype(np.float32) if textured and uv else np.zeros((1, 2), np.float32),
                         dtype=wp.vec2, device=device)
        s.colors = wp.array(np.concatenate(rgb).astype(np.float32) if coloured and rgb else np.ones((1, 3), np.float32),
                            dtype=wp.vec3, device=device)
        images, index = [np.ones((1, 1, 3), np.float32)], {}  # slot 0: white
        slots = {"ka": [], "kd": [], "ks": []}
        for mat in materials:
            for key, rows in slots.items():
                t = getattr(mat, f"{key}_texture", None)
                slot = TextureSlot()
                slot.image, slot.u_map, slot.v_map = 0, wp.vec3(1.0, 0.0, 0.0), wp.vec3(0.0, 1.0, 0.0)
                slot.c0, slot.c1 = wp.vec3(1.0), wp.vec3(1.0)
                if t is not None:
                    a = t.uv_transform
                    slot.u_map, slot.v_map = wp.vec3(*a[:3]), wp.vec3(*a[3:])
                    if t.checker is not None:
                        slot.image, slot.c0, slot.c1 = CHECKER, wp.vec3(*t.checker[0]), wp.vec3(*t.checker[1])
                    else:
                        if id(t.image) not in index:  # an image several materials share is held once
                            index[id(t.image)] = len(images)
                            images.append(t.image)
                        slot.image = index[id(t.image)]
                rows.append(slot)
        s.ka_map, s.kd_map, s.ks_map = (wp.array(slots[k], dtype=TextureSlot, device=device) for k in ("ka", "kd", "ks"))
        # Warp's textures hold 1, 2 or 4 channels: RGB is padded to RGBA.
        self.texture_objects = [wp.Texture2D(np.ascontiguousarray(np.concatenate([a, np.ones(a.shape[:2] + (1,), np.float32)], -1)),
                                             filter_mode=wp.TextureFilterMode.LINEAR,
                                             address_mode=wp.TextureAddressMode.WRAP, normalized_coords=True,
                                             device=device) for a in images]
        s.textures = wp.array(self.texture_objects, dtype=wp.Texture2D, device=device)  # the objects kept alive with it
        self.texture_bytes = int(sum(a.shape[0] * a.shape[1] * 16 for a in images))

    def object_tables(self):
        """Per triangle, its object's index in scene.objects, and per object its first triangle: what
        the object and face AOVs read. Built on first use (4 bytes a triangle), so renders without
        those AOVs never hold them."""
        if self.object_ids is None:
            counts = self.object_face_counts or [1]  # an empty scene's one degenerate triangle
            first = np.concatenate([[0], np.cumsum(counts)[:-1]]).astype(np.int32)
            tri_object = np.repeat(np.arange(len(counts), dtype=np.int32), counts)
            self.object_ids = (wp.array(tri_object, dtype=wp.int32, device=self.device),
                               wp.array(first, dtype=wp.int32, device=self.device))
        return self.object_ids

    def uv_tables(self):
        """Every vertex's texture coordinates ((0, 0) on objects without) and, per object, whether it has
        them: what the uv AOV reads. Built on first use (8 bytes a vertex), like object_tables."""
        if self.object_uv is None:
            uv = [np.zeros((n, 2)) if u is None else u for n, u in self._object_uv] or [np.zeros((3, 2))]
            has = [int(u is not None) for _, u in self._object_uv] or [0]
            self.object_uv = (wp.array(np.concatenate(uv).astype(np.float32), dtype=wp.vec2, device=self.device),
                              wp.array(np.asarray(has, np.int32), dtype=wp.int32, device=self.device))
        return self.object_uv
