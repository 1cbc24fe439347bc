"""The scene flattened for the kernels: one triangle set in float32 relative to a frame origin, with a
per-triangle material slot, vertex normals for smooth objects, uvs and colours per vertex where the
scene has them, and per-frame tables: the materials (Phong with its texture slots, and the dielectrics'
ior, k_t and sigma), the textures, the lights, and the medium the eye is in.

Coordinates are made relative to the frame origin (bvh.frame_origin: the objects' centre, or an eye
beyond the region a BVH built there covers) in float64 before the cast to float32, so a scene far from
the world origin keeps the precision it has near it. Camera rays start at the float32 eye - origin.
Later frames reuse the triangles and the BVH while their eye keeps that origin; the origin depends on
the objects and the eye alone, so a reused frame is a fresh build's image to the bit.
"""

from __future__ import annotations

import numpy as np
from .._warp import wp
from ..scene import (EMITTER_MATERIAL, EMITTER_MATERIAL_NAME, drawn_objects, emitter_of_triangles, emitter_samples,
                     environment_samples, environment_texels, eye_medium, emitting_triangles, light_hull, spread_strata,
                     to_world, vertex_normals)
from .bvh import build_mesh, eye_reach, frame_origin, objects_center, refit_mesh
from .shadow_grid import ShadowGrid, empty_grid

# How a texture's coordinate outside [0, 1] is read, per axis (scene.Texture.wrap): Warp's address modes'
# numbers (wp.TextureAddressMode WRAP, CLAMP, MIRROR), whose CPU sampler kernels.texture.bilinear follows.
TEXTURE_WRAP, TEXTURE_CLAMP, TEXTURE_MIRROR = 0, 1, 2
WRAP_MODES = {"repeat": TEXTURE_WRAP, "clamp": TEXTURE_CLAMP, "mirror": TEXTURE_MIRROR}
UNTEXTURED, IMAGE, CHECKER = 0, 1, -1  # TextureSlot.image: the colour as it is, an image's texels, the checker


@wp.struct
class TextureSlot:
    """How one material colour (ka, kd or ks) is textured: ``image`` says how (UNTEXTURED: the colour as it
    is; IMAGE: the bilinear texel of the width x height image stored row by row, row 0 at v = 0, from
    ``offset`` in SceneData.texels, read per axis as ``wrap`` says; CHECKER: c0 and c1 on alternate unit
    squares), and the uv map u' = u_map . (u, v, 1), v' = v_map . (u, v, 1)."""

    image: int
    offset: int
    width: int
    height: int
    wrap: wp.vec2i
    u_map: wp.vec3
    v_map: wp.vec3
    c0: wp.vec3
    c1: wp.vec3


LIGHT_POINT, LIGHT_SPOT, LIGHT_DIRECTIONAL = 0, 1, 2  # LightShape.kind, for Light.type


@wp.struct
class LightShape:
    """What a light has beyond the seed's point light, read by shading's general light model: its kind,
    the direction it travels along (spot axis, sun; unit), a spot's cone as Mitsuba's ``spot`` keeps it
    (cos cutoff, cos beam, the cutoff and 1 / (cutoff - beam) in radians, 0 where there is no ramp) and
    whether it falls off as 1 / r^2."""

    kind: int
    direction: wp.vec3
    cos_cutoff: float
    cos_beam: float
    cutoff: float
    inv_ramp: float
    inverse_square: int


def light_shape(light) -> LightShape:
    """A scene Light's LightShape (the angles converted in float64, then rounded to float32)."""
    shape = LightShape()
    shape.kind = {"point": LIGHT_POINT, "spot": LIGHT_SPOT, "directional": LIGHT_DIRECTIONAL}[light.type]
    shape.direction = wp.vec3(*(light.direction if light.direction is not None else (0.0, 0.0, 0.0)))
    cutoff, beam = np.radians(light.cutoff_angle), np.radians(light.beam)
    shape.cos_cutoff, shape.cos_beam = float(np.cos(cutoff)), float(np.cos(beam))
    shape.cutoff = float(cutoff)
    shape.inv_ramp = float(1.0 / (cutoff - beam)) if cutoff > beam else 0.0
    shape.inverse_square = int(light.falloff == "inverse_square")
    return shape


def texture_slots(materials, per_use: bool = False) -> tuple:
    """(slots, images, placed): per colour ("ka", "kd", "ks") the TextureSlot of each material in
    ``materials``; the images their texels hold, in order (texel_array: a 1 x 1 white one first, so that no
    slot's offset is 0); and where each image colour lies, {(material index, colour): (offset, height,
    width)}. An image several colours share is held once, or with ``per_use`` once per colour (the
    gradient's replay: each its own adjoint)."""
    images, offsets, placed = [np.ones((1, 1, 3), np.float32)], {}, {}
    slots = {"ka": [], "kd": [], "ks": []}
    offset = 1
    for i, mat in enumerate(materials or [None]):
        for key, rows in slots.items():
            t = getattr(mat, f"{key}_texture", None) if mat is not None else None
            slot = TextureSlot()
            slot.image, slot.offset, slot.width, slot.height = UNTEXTURED, 0, 1, 1
            slot.wrap = wp.vec2i(TEXTURE_WRAP, TEXTURE_WRAP)
            slot.u_map, slot.v_map = wp.vec3(1.0, 0.0, 0.0), wp.vec3(0.0, 1.0, 0.0)
            slot.c0, slot.c1 = wp.vec3(1.0), wp.vec3(1.0)
            if t is not None:
                a = t.uv_transform
                slot.u_map, slot.v_map = wp.vec3(*a[:3]), wp.vec3(*a[3:])
                if t.checker is not None:
                    slot.image, slot.c0, slot.c1 = CHECKER, wp.vec3(*t.checker[0]), wp.vec3(*t.checker[1])
                else:
                    h, w = t.image.shape[:2]
                    name = (i, key) if per_use else id(t.image)
                    if name not in offsets:
                        offsets[name] = offset
                        images.append(t.image)
                        offset += h * w
                    # Per axis: glTF's wrapS and wrapT, USD's, MTL's -clamp; repeat unless the file says otherwise.
                    slot.image, slot.offset, slot.width, slot.height = IMAGE, offsets[name], w, h
                    slot.wrap = wp.vec2i(WRAP_MODES[t.wrap[0]], WRAP_MODES[t.wrap[1]])
                    placed[(i, key)] = (offsets[name], h, w)
            rows.append(slot)
    return slots, images, placed


def texel_array(images, device, requires_grad: bool = False) -> wp.array:
    """The images' texels (RGB; an image's channels beyond three left out), one after another, row by row."""
    rows = [np.asarray(a, np.float32)[..., :3].reshape(-1, 3) for a in images]
    return wp.array(np.concatenate(rows), dtype=wp.vec3, device=device, requires_grad=requires_grad)


@wp.struct
class AreaLights:
    """The area lights (scene.area), read only where a scene has some (EffectSet.area_lights): per light its
    radiance L_e and its first sample (first[num] the total), per sample its point (relative to the frame
    origin), its unit normal on the emitting side and the area it stands for (A / N), and per triangle the
    area light it emits for (-1: none). With render.light_spread, ``first`` has ``strata`` starts a light (pixel
    sample stratum s of light e: first[e strata + s]), its points ordered by stratum, each dA times strata; with
    render.area_estimator = "analytic", ``corners`` holds the triangles each light's diffuse term is integrated
    over in closed form (three corners each; none for a disk or a sphere), light e's from polygon[e] to
    polygon[e + 1], and ``spheres`` each sphere light's centre and radius (radius 0: not a sphere), all read
    only then. ``hull`` holds four corners a light (scene.light_hull) around all its points, ``hulled`` 1 for a
    light that has one, and ``clear`` 1 where a hit may prove its shadow rays clear of the scene
    (kernels/clearance.py; 0 where the frame traces every shadow ray, shadow_query "bvh")."""

    num: int
    strata: int
    first: wp.array(dtype=wp.int32)
    radiance: wp.array(dtype=wp.vec3)
    points: wp.array(dtype=wp.vec3)
    normals: wp.array(dtype=wp.vec3)
    dA: wp.array(dtype=float)
    tri_emitter: wp.array(dtype=wp.int32)
    corners: wp.array(dtype=wp.vec3)
    polygon: wp.array(dtype=wp.int32)
    spheres: wp.array(dtype=wp.vec4)
    hull: wp.array(dtype=wp.vec3)
    hulled: wp.array(dtype=wp.int32)
    clear: int


@wp.struct
class Environment:
    """The environment light (scene/environment.py), read only where a scene has one (EffectSet.environment):
    its radiance texels (height rows of width, row 0 at the +y pole, the first column repeated last), the
    rotation from world to its local directions, and its fixed directions (world, unit) with their weights
    L / (pdf N). With render.light_spread, the directions ordered by the pixel sample that takes them (lattice
    point n to n mod ``strata``: each share itself a lattice over the whole sky), each weight times ``strata``:
    share s is num // strata directions, one more where s < num mod strata (environment_share)."""

    texels: wp.array(dtype=wp.vec3)
    width: int
    height: int
    to_local: wp.mat33
    num: int
    directions: wp.array(dtype=wp.vec3)
    weights: wp.array(dtype=wp.vec3)
    strata: int


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
    texels: wp.array(dtype=wp.vec3)  # the images' texels, linear RGB, one image after another (TextureSlot)
    ior: wp.array(dtype=float)  # eta of a dielectric, 0 for an opaque material
    transmittance: wp.array(dtype=wp.vec3)  # k_t
    absorption: wp.array(dtype=wp.vec3)  # sigma per scene unit
    cull: wp.array(dtype=wp.int32)  # per material, 1: single-sided, its back faces skipped (EffectSet.culling)
    eye_medium: int  # the dielectric material holding the eye, -1: air
    light_pos: wp.array(dtype=wp.vec3)  # relative to the frame origin; NaN for a directional light
    light_color: wp.array(dtype=wp.vec3)
    light_shape: wp.array(dtype=LightShape)  # read only by the general light model (EffectSet.light_model)
    num_lights: int
    ambient: wp.vec3  # C_amb
    background: wp.vec3
    shadow_grid: ShadowGrid  # the light-space structure (shadow_grid.py), read where shadow rays use it
    area: AreaLights  # a stand-in of no lights where the scene has none
    env: Environment  # a stand-in of a black environment where the scene has none


def light_strata(scene, fx) -> int:
    """The pixel samples an area light's points (and an environment's directions) are spread over in a frame of
    effect set ``fx``: spp where it spreads them (fx.light_spread: render.light_spread, spp > 1 and supersampling
    on), else 1 (every pixel sample takes every point). The tables' layouts (AreaLights, Environment) and the
    kernel's switch agree by this."""
    return scene.render.spp if fx.light_spread else 1


def _spread(area, samples: list, k: int, strata: int) -> tuple[list, np.ndarray]:
    """The lights' (points, normals, dA) ordered by the pixel sample that takes them (spread_strata), dA times
    ``strata``, and the start of each light's stratum (``strata`` a light, then the total)."""
    out, counts = [], []
    for light, (p, n, w) in zip(area, samples):
        s = spread_strata(light, k, strata)
        order = np.argsort(s, kind="stable")
        out.append((p[order], n[order], w[order] * strata))
        counts.append(np.bincount(s, minlength=strata))
    return out, np.concatenate([[0], np.cumsum(np.concatenate(counts))])


def vertex_colors(objects) -> np.ndarray:
    """The kernels' per-vertex colours of ``objects`` (float32): each object's, white for one without, or
    one white stand-in where none has any."""
    coloured = any(getattr(o, "colors", None) is not None for o in objects)
    rgb = [o.colors if getattr(o, "colors", None) is not None else np.ones((len(o.vertices), 3)) for o in objects]
    return np.concatenate(rgb).astype(np.float32) if coloured and rgb else np.ones((1, 3), np.float32)


class Geometry:
    """Owns the device arrays and the BVH for one set of objects, in coordinates relative to
    ``origin`` (default: bvh.frame_origin, the objects' centre or a far eye); ``scene_data(scene)``
    gives the kernels a frame's view."""

    def __init__(self, scene, device="cpu", bvh_constructor: str = "sah", build_bvh: bool = True, origin=None):
        # build_bvh=False: the Z-buffer needs the triangles and tables but never a ray query, and
        # its timings must not pay for a BVH (about 1.5 s for a million triangles on the CPU).
        self.device = device
        objects = drawn_objects(scene)  # the scene's objects, then the area lights' own shapes
        self.center, self.center_reach = objects_center(objects)
        # The origin the rule gives this eye (planned) and the one used (tests may move it: origin=).
        self.planned_origin = self.origin_for(scene.camera.eye)
        self.origin = np.asarray(self.planned_origin if origin is None else origin, np.float64)  # world position
        # Stand-ins and uploads kept for the next frames (scene_data, _textures), made on first use.
        self._no_grid = None  # the ShadowGrid of no grid
        self._no_area = None  # the AreaLights of no area lights
        self._no_env = None  # the Environment of none
        self._no_uvs = None  # the uv array of a frame without textures
        self._texture_cache: dict = {}  # the last frame's images (and their ids) and their texels: uploaded once
        # A triangle's material is a slot: the objects' material names in order of first use, so the
        # triangle arrays depend on the objects alone and a frame with other materials only swaps tables.
        self.material_names = list(dict.fromkeys(obj.material for obj in objects))
        faces, mats, smooth, owner = [], [], [], []
        base = 0
        for index, obj in enumerate(objects):
            owner.append(np.full(len(obj.faces), index, np.int32))
            faces.append(obj.faces + base)
            mats.append(np.full(len(obj.faces), self.material_names.index(obj.material), np.int32))
            smooth.append(np.full(len(obj.faces), int(obj.smooth), np.int32))
            base += len(obj.vertices)
        if not faces:  # an empty scene still gets a (degenerate, never hit) mesh so kernels can run
            faces, mats, smooth = [np.zeros((1, 3), np.int64)], [np.zeros(1, np.int32)], [np.zeros(1, np.int32)]
            owner = [np.zeros(1, np.int32)]
            self.triangle_count = 0
        else:
            self.triangle_count = int(sum(len(f) for f in faces))
        self.points_np, normals = self._placed(objects)
        self.indices_np = np.ascontiguousarray(np.concatenate(faces).reshape(-1), np.int32)
        self.tri_material_np = np.concatenate(mats)
        self.tri_smooth_np = np.concatenate(smooth)
        self.tri_object_np = np.concatenate(owner)  # the index of each triangle's object
        self.reach = float(np.abs(self.points_np).max(initial=0.0))  # the largest |coordinate|
        self.eye_reach = eye_reach(self.points_np)  # E: how far an eye may move and keep this BVH
        self._boxes = None  # triangle_boxes(), once asked for
        self.object_face_counts = [len(obj.faces) for obj in objects]
        self.object_ids = None  # object_tables(), once built
        self._object_uv = [(len(obj.vertices), getattr(obj, "uv", None)) for obj in objects]
        self.object_uv = None  # uv_tables(), once built
        self._uv_array = None  # uv_array(), once a frame has textures or the uv AOV is asked for
        colors = vertex_colors(objects)

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
        self.normals = wp.array(normals, dtype=wp.vec3, device=d)
        self.tri_material = wp.array(self.tri_material_np, dtype=wp.int32, device=d)
        self.tri_smooth = wp.array(self.tri_smooth_np, dtype=wp.int32, device=d)
        self.colors = wp.array(colors, dtype=wp.vec3, device=d)  # white where the scene has no vertex colours
        self._tables = None
        self.data = self.scene_data(scene)  # the tables of the scene it was built for

    def _placed(self, objects) -> tuple[np.ndarray, np.ndarray]:
        """The points relative to the origin (float64, then float32) and the vertex normals (float32; zero
        where an object is flat) of ``objects``; for no objects, the three points of the stand-in triangle."""
        verts, normals = [], []
        for obj in objects:
            verts.append(obj.vertices - self.origin)
            if obj.smooth:
                given = getattr(obj, "normals", None)
                normals.append(given if given is not None else vertex_normals(obj.vertices, obj.faces))
            else:
                normals.append(np.zeros_like(obj.vertices))
        if not verts:
            verts, normals = [np.zeros((3, 3))], [np.zeros((3, 3))]
        return np.ascontiguousarray(np.concatenate(verts), np.float32), np.concatenate(normals).astype(np.float32)

    def move_vertices(self, scene) -> bool:
        """Take ``scene``'s objects' vertices, the objects being this Geometry's but for where their
        vertices are: the frame origin planned again for them and the eye, the points and vertex
        normals written over in place, and the BVH refit over their padded boxes rather than rebuilt.
        The points are then a fresh build's to the bit; only the BVH's tree differs, which can break a
        tie between two equal hits the other way. False (nothing changed) where the objects differ in
        more than that, or there is no BVH: the caller builds a new Geometry."""
        objects = drawn_objects(scene)
        if self.mesh is None or self.triangle_count == 0 or len(objects) != len(self.object_face_counts):
            return False
        if any(len(o.faces) != n or len(o.vertices) != m for o, n, (m, _) in
               zip(objects, self.object_face_counts, self._object_uv)):
            return False
        self.center, self.center_reach = objects_center(objects)
        self.planned_origin = self.origin = self.origin_for(scene.camera.eye)
        self.points_np, normals = self._placed(objects)
        self.reach = float(np.abs(self.points_np).max(initial=0.0))
        self.eye_reach = eye_reach(self.points_np)
        self._boxes, self._tables = None, None  # the light positions and the eye's medium follow the origin
        refit_mesh(self.mesh, self.points, self.indices, self.points_np, self.indices_np, self.eye_reach)
        self.normals.assign(normals)
        self.data = self.scene_data(scene)
        return True

    def recolor(self, scene):
        """Take ``scene``'s objects' vertex colours, the objects being this Geometry's but for their colours
        (present on the same objects, of the same shapes): written over the kept array in place, as a fresh
        build would make it (vertex_colors), the kernels' tables sharing it."""
        self.colors.assign(vertex_colors(drawn_objects(scene)))

    def triangle_boxes(self) -> tuple[np.ndarray, np.ndarray]:
        """Each triangle's (lowest, highest) corner in float64, computed once for these points."""
        if self._boxes is None:
            tri = self.points_np.astype(np.float64)[self.indices_np.reshape(-1, 3)]
            self._boxes = (tri.min(axis=1), tri.max(axis=1))
        return self._boxes

    def origin_for(self, eye) -> np.ndarray:
        """The frame origin bvh.frame_origin gives these objects seen from ``eye``: a frame reuses this
        Geometry only where that is the origin it was planned with, so its image is a fresh build's."""
        return frame_origin(self.center, self.center_reach, eye)

    def eye_offset(self, eye) -> np.ndarray:
        """Where the camera rays of an eye at world position ``eye`` start: eye - origin, computed in
        float64 and rounded to float32 as the points were (exactly 0 at the origin)."""
        return (np.asarray(eye, np.float64) - self.origin).astype(np.float32)

    def covers(self, eye) -> bool:
        """Whether camera rays from ``eye`` (world) keep the BVH's guarantees: within eye_reach of the
        origin on every axis (bvh.py: the padding's slab-test argument)."""
        return bool(np.abs(np.asarray(eye, np.float64) - self.origin).max() <= self.eye_reach)

    def light_positions(self, scene) -> np.ndarray:
        """The kernels' light positions (L, 3) of the Whitted lights (all but area lights): relative to the
        origin in float64, then float32; NaN for a directional light, which has none (the shadow grid then
        sends its rays to the BVH)."""
        return np.asarray([np.asarray(l.position, np.float64) - self.origin if l.position is not None
                           else np.full(3, np.nan) for l in scene.whitted_lights], np.float32).reshape(-1, 3)

    def slot_materials(self, scene) -> list:
        """The Material of each material slot: the scene's, and EMITTER_MATERIAL for the slot of the area
        lights' own shapes (drawn_objects), which the scene's materials do not name."""
        return [EMITTER_MATERIAL if n == EMITTER_MATERIAL_NAME else scene.materials[n] for n in self.material_names]

    def scene_data(self, scene, shadow_grid: ShadowGrid | None = None, strata: int = 1,
                   clearance: bool = True) -> SceneData:
        """The kernels' view of these triangles for a frame of ``scene``: its materials and textures,
        lights, ambient, background and the eye's medium as small new arrays where they changed, and the
        shadow rays' grid if one is given, and the area lights' points spread over ``strata`` pixel samples
        (light_strata), their shadow rays proven clear where a hit can (``clearance``, kernels/clearance.py: the
        same image, so set on the kept tables without making them again); the triangle arrays and the BVH are
        shared, never rebuilt."""
        m = self.slot_materials(scene)
        dielectric = any(x.dielectric for x in m)
        area = scene.area_lights
        # With glass, the medium the eye is in (eye_medium) depends on the eye too.
        key = (tuple(m), tuple(scene.lights), tuple(scene.render.ambient), tuple(scene.render.background),
               id(shadow_grid), tuple(scene.camera.eye) if dielectric else None,
               (scene.render.light_samples, scene.render.area_estimator, strata) if area else None,
               (scene.render.light_samples, strata) if scene.environment else None)
        if self._tables is not None and self._tables[0] == key:
            return _cleared(self._tables[1], clearance)
        d, lights = self.device, scene.whitted_lights
        s = SceneData()
        s.mesh = self.mesh.id if self.mesh is not None else wp.uint64(0)
        s.points = self.points
        s.indices = self.indices
        s.normals = self.normals
        s.tri_material = self.tri_material
        s.tri_smooth = self.tri_smooth
        s.colors = self.colors
        vec = lambda rows: wp.array(np.asarray(rows, np.float32).reshape(-1, 3), dtype=wp.vec3, device=d)
        s.ka = vec([x.ka for x in m] or [[0, 0, 0]])
        s.kd = vec([x.kd for x in m] or [[0, 0, 0]])
        s.ks = vec([x.ks for x in m] or [[0, 0, 0]])
        s.kr = vec([x.reflectivity for x in m] or [[0, 0, 0]])
        s.shininess = wp.array(np.asarray([x.shininess for x in m] or [0.0], np.float32), dtype=float, device=d)
        textures = self._textures(s, m)
        s.ior = wp.array(np.asarray([x.ior or 0.0 for x in m] or [0.0], np.float32), dtype=float, device=d)
        s.transmittance = vec([x.transmittance for x in m] or [[1, 1, 1]])
        s.absorption = vec([x.absorption for x in m] or [[0, 0, 0]])
        s.cull = wp.array(np.asarray([not x.double_sided for x in m] or [0], np.int32), dtype=wp.int32, device=d)
        # Only the tracer follows rays into a medium (the Z-buffer's geometry has no BVH).
        medium = eye_medium(scene) if self.mesh is not None and dielectric else None
        s.eye_medium = self.material_names.index(medium) if medium is not None else -1
        s.light_pos = vec(self.light_positions(scene) if lights else [[0, 0, 0]])
        s.light_color = vec([l.color for l in lights] or [[0, 0, 0]])
        s.light_shape = wp.array([light_shape(l) for l in lights] or [LightShape()], dtype=LightShape, device=d)
        s.num_lights = len(lights)
        s.ambient = wp.vec3(*scene.render.ambient)
        s.background = wp.vec3(*scene.render.background)
        if shadow_grid is None and self._no_grid is None:
            self._no_grid = empty_grid(d)
        s.shadow_grid = shadow_grid if shadow_grid is not None else self._no_grid
        s.area = self._area_lights(scene, area, strata)
        s.env = self._environment(scene.environment, scene.render.light_samples, strata)
        self._tables = (key, s, shadow_grid, textures)  # the grid and images kept alive with their ids
        return _cleared(s, clearance)

    def _area_lights(self, scene, area: list, strata: int = 1) -> AreaLights:
        """The area lights' table for a frame: light_samples points each, relative to the origin (float64,
        then float32), and each triangle's emitter; a stand-in of no lights (kept) for a scene without."""
        d = self.device
        if not area:
            if self._no_area is None:
                a = AreaLights()
                a.num = 0
                a.strata = 1
                a.corners = wp.zeros(1, dtype=wp.vec3, device=d)
                a.polygon = wp.zeros(1, dtype=wp.int32, device=d)
                a.spheres = wp.zeros(1, dtype=wp.vec4, device=d)
                a.hull = wp.zeros(4, dtype=wp.vec3, device=d)
                a.hulled = wp.zeros(1, dtype=wp.int32, device=d)
                a.clear = 0
                a.first = wp.zeros(1, dtype=wp.int32, device=d)
                a.radiance, a.points, a.normals = (wp.zeros(1, dtype=wp.vec3, device=d) for _ in range(3))
                a.dA = wp.zeros(1, dtype=float, device=d)
                a.tri_emitter = wp.full(1, -1, dtype=wp.int32, device=d)
                self._no_area = a
            return self._no_area
        k = int(np.sqrt(scene.render.light_samples))
        samples = [emitter_samples(scene, light, k) for light in area]
        first = np.concatenate([[0], np.cumsum([len(p) for p, _, _ in samples])])
        if strata > 1:
            samples, first = _spread(area, samples, k, strata)
        vec = lambda rows: wp.array(np.asarray(rows, np.float32).reshape(-1, 3), dtype=wp.vec3, device=d)
        a = AreaLights()
        a.num = len(area)
        a.strata = strata
        a.first = wp.array(first.astype(np.int32), dtype=wp.int32, device=d)
        a.radiance = vec([l.radiance for l in area])
        a.points = vec(np.concatenate([p - self.origin for p, _, _ in samples]))
        a.normals = vec(np.concatenate([n for _, n, _ in samples]))
        a.dA = wp.array(np.concatenate([w for _, _, w in samples]).astype(np.float32), dtype=float, device=d)
        a.tri_emitter = wp.array(emitter_of_triangles(scene), dtype=wp.int32, device=d)
        tris = [emitting_triangles(scene, l) if scene.render.area_estimator == "analytic" else np.zeros((0, 3, 3))
                for l in area]
        a.corners = vec(np.concatenate([t.reshape(-1, 3) - self.origin for t in tris] + [np.zeros((1, 3))]))
        a.polygon = wp.array(np.concatenate([[0], np.cumsum([len(t) for t in tris])]).astype(np.int32),
                             dtype=wp.int32, device=d)
        spheres = [[*(np.asarray(l.center if l.center is not None else (0.0, 0.0, 0.0)) - self.origin), l.radius]
                   if l.shape == "sphere" and scene.render.area_estimator == "analytic" else [0.0] * 4 for l in area]
        a.spheres = wp.array(np.asarray(spheres, np.float32), dtype=wp.vec4, device=d)
        hulls = [light_hull(scene, l) for l in area]
        a.hull = vec([h - self.origin if h is not None else np.zeros((4, 3)) for h in hulls])
        a.hulled = wp.array(np.asarray([h is not None for h in hulls], np.int32), dtype=wp.int32, device=d)
        a.clear = 0
        return a

    def _environment(self, light, light_samples: int, strata: int = 1) -> Environment:
        """The environment's table for a frame: its texels, rotation and light_samples directions, spread over
        ``strata`` pixel samples (light_strata); a black stand-in (kept) for a scene without."""
        d = self.device
        e = Environment()
        if light is None:
            if self._no_env is None:
                e.texels = wp.zeros(4, dtype=wp.vec3, device=d)
                e.width, e.height, e.to_local, e.num = 2, 2, wp.mat33(np.eye(3)), 0
                e.directions, e.weights = wp.zeros(1, dtype=wp.vec3, device=d), wp.zeros(1, dtype=wp.vec3, device=d)
                e.strata = 1
                self._no_env = e
            return self._no_env
        texels = environment_texels(light)
        directions, weights = environment_samples(light, light_samples)
        order = np.argsort(np.arange(len(directions)) % strata, kind="stable")
        directions, weights = directions[order], weights[order] * strata
        vec = lambda rows: wp.array(np.asarray(rows, np.float32).reshape(-1, 3), dtype=wp.vec3, device=d)
        e.texels = vec(texels.reshape(-1, 3))
        e.height, e.width = texels.shape[:2]
        e.to_local = wp.mat33(to_world(light).T.astype(np.float32))
        e.num = len(directions)
        e.directions = vec(directions if len(directions) else np.zeros((1, 3)))
        e.weights = vec(weights if len(weights) else np.zeros((1, 3)))
        e.strata = strata
        return e

    def uv_array(self):
        """Every vertex's texture coordinates, (0, 0) on objects without: what textured shading and the uv
        AOV read. Built on first use (8 bytes a vertex), so scenes without textures never hold it."""
        if self._uv_array is None:
            uv = [np.zeros((n, 2)) if u is None else u for n, u in self._object_uv] or [np.zeros((3, 2))]
            self._uv_array = wp.array(np.concatenate(uv).astype(np.float32), dtype=wp.vec2, device=self.device)
        return self._uv_array

    def _textures(self, s: SceneData, materials) -> tuple:
        """A frame's uvs, texture slots and texels; one-element stand-ins where it has none (the kernels
        read them only under the texture switch). Returns what must outlive ``s``: its images (whose ids key
        the texels kept for the next frames, so that an image is uploaded once while frames keep using it)."""
        device = self.device
        textured = any(mat.textures for mat in materials)
        if textured:
            s.uvs = self.uv_array()
        else:
            if self._no_uvs is None:
                self._no_uvs = wp.zeros(1, dtype=wp.vec2, device=device)
            s.uvs = self._no_uvs
        slots, images, _ = texture_slots(materials)
        s.ka_map, s.kd_map, s.ks_map = (wp.array(slots[k], dtype=TextureSlot, device=device) for k in ("ka", "kd", "ks"))
        key = tuple(id(a) for a in images)  # the images themselves are held with it: no id is reused meanwhile
        if self._texture_cache.get("key") != key:
            self._texture_cache = {"key": key, "images": images, "texels": texel_array(images, device)}
        s.texels = self._texture_cache["texels"]
        self.texture_bytes = int(sum(a.shape[0] * a.shape[1] * 12 for a in images))
        return images

    def object_tables(self):
        """Per triangle, its object's index in scene.objects, and per object its first triangle: what
        the object and face AOVs read. Built on first use (4 bytes a triangle), so renders without
        those AOVs never hold them."""
        if self.object_ids is None:
            counts = self.object_face_counts or [1]  # an empty scene's one degenerate triangle
            first = np.concatenate([[0], np.cumsum(counts)[:-1]]).astype(np.int32)
            self.object_ids = (wp.array(self.tri_object_np, dtype=wp.int32, device=self.device),
                               wp.array(first, dtype=wp.int32, device=self.device))
        return self.object_ids

    def uv_tables(self):
        """uv_array() and, per object, whether it has texture coordinates: what the uv AOV reads."""
        if self.object_uv is None:
            has = [int(u is not None) for _, u in self._object_uv] or [0]
            self.object_uv = (self.uv_array(), wp.array(np.asarray(has, np.int32), dtype=wp.int32, device=self.device))
        return self.object_uv

    def material_indices(self, scene) -> np.ndarray:
        """Per material slot, the material's index in scene.materials (what the material AOV reports); -1 for
        the area lights' own shapes, which have none of the scene's."""
        names = list(scene.materials)
        return np.asarray([names.index(n) if n in scene.materials else -1 for n in self.material_names] or [0], np.int32)


def _cleared(s: SceneData, clearance: bool) -> SceneData:
    """``s`` with its area lights' shadow rays proven clear where a hit can, or not (AreaLights.clear)."""
    if s.area.num > 0 and s.area.clear != int(clearance):
        area = s.area
        area.clear = int(clearance)
        s.area = area
    return s
