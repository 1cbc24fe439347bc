"""A warprt Scene rendered by Mitsuba 3: the same Whitted model on Mitsuba's own sensor, sampler,
film, Embree intersection and ray spawning, sharing no tracing code with src/warprt.

Model (the seed's Figure 3, as warprt defines it), per colour channel, two-sided surfaces:
    I = C_amb ka + sum_l vis_l C_l (kd max(0, n.L) + ks max(0, r.v)^n) + k_r I(reflected),
vis_l = 0 when n.L <= 0 or the shadow ray is blocked; a miss returns the background; max_depth ray levels.
With glass, + F I(reflected) + (1 - F) k_t I(refracted) at a dielectric, each segment inside weighted
by exp(-sigma d): the ray tree of ray_tree.py, level by level, which mi.render cannot branch into.
"""

from __future__ import annotations

import math
import os
import sys
from dataclasses import dataclass

import numpy as np

from warprt.scene import ObjectCache

# Dr.Jit 1.5 needs an LLVM it can drive; Debian 12's libLLVM 15 crashes it ("Cannot select: fminimum").
LLVM_PATH = "/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1"
INTEGRATOR = "warprt_whitted"

_modules = None  # (mi, dr) once imported and the variant is set
# Module globals rather than closure variables: @dr.syntax recompiles sample() against the
# module's globals, so the names it uses must live here.
mi = None
dr = None


def mitsuba():
    """Import Mitsuba once: ``llvm_ad_rgb`` (vectorised, all cores) when Dr.Jit finds an LLVM,
    else ``scalar_rgb`` (Python called per ray, slow) with a note on stderr saying so.
    WARPRT_MITSUBA_VARIANT forces a variant (the tests use it to exercise the fallback)."""
    global _modules, mi, dr
    if _modules is not None:
        return _modules
    if "DRJIT_LIBLLVM_PATH" not in os.environ and os.path.exists(LLVM_PATH):
        os.environ["DRJIT_LIBLLVM_PATH"] = LLVM_PATH  # read when drjit is first imported
    import drjit
    import mitsuba

    mi, dr = mitsuba, drjit
    variant = os.environ.get("WARPRT_MITSUBA_VARIANT")
    if not variant:
        if dr.has_backend(dr.JitBackend.LLVM):
            variant = "llvm_ad_rgb"
        else:
            variant = "scalar_rgb"
            print("reference: Dr.Jit found no usable LLVM (install libllvm19 and set DRJIT_LIBLLVM_PATH); "
                  "falling back to Mitsuba's scalar_rgb variant, which is much slower", file=sys.stderr)
    mi.set_variant(variant)
    _register_integrator(mi, dr)
    _modules = (mi, dr)
    return _modules


def mitsuba_variant() -> str:
    mi, _ = mitsuba()
    return mi.variant()


@dataclass(frozen=True)
class Switches:
    """Which terms the reference evaluates: the same switches as a warprt EffectSet."""

    ambient: bool = True
    diffuse: bool = True
    specular: bool = True
    shadows: bool = True
    max_depth: int = 3  # ray levels; 1 = primary rays only
    spp: int = 1  # k*k stratified samples at the stratum centres
    smooth: bool = True  # interpolated vertex normals on objects marked smooth
    reflection: bool = True  # mirrors (k_r) spawn reflected rays
    refraction: bool = False  # dielectrics (ior) spawn reflected and refracted rays: the ray tree
    absorption: bool = False  # Beer's law inside dielectrics

    @classmethod
    def for_effects(cls, fx, settings) -> "Switches":
        """The switches that match warprt rendering ``settings`` (a RenderSettings) with EffectSet ``fx``."""
        return cls(ambient=fx.ambient, diffuse=fx.diffuse, specular=fx.specular, shadows=fx.shadows,
                   max_depth=settings.max_depth if fx.reflection or fx.refraction else 1,
                   spp=settings.spp if fx.supersampling else 1, smooth=fx.smooth, reflection=fx.reflection,
                   refraction=fx.refraction, absorption=fx.absorption)

    @property
    def tree(self) -> bool:
        """Whether the render needs the ray tree (ray_tree.py) rather than mi.render's single path."""
        return self.refraction or self.absorption


def _register_integrator(mi, dr):
    class WhittedIntegrator(mi.SamplingIntegrator):
        """Whitted ray tracing with Phong shading, point lights, hard shadows and mirrors."""

        def __init__(self, props):
            super().__init__(props)
            self.switches = Switches()
            self.tables = None  # _Tables of the scene being rendered, set by MitsubaScene

        def material(self, si, active):
            """(ka, kd, ks, k_r, shininess) of the hit shape, from tables keyed by the shape."""
            t = self.tables
            if t.jit:
                # A ShapePtr in a JIT variant is the shape's index in Dr.Jit's instance registry.
                idx = dr.reinterpret_array(mi.UInt32, si.shape)
                return (dr.gather(mi.Color3f, t.ka, idx, active), dr.gather(mi.Color3f, t.kd, idx, active),
                        dr.gather(mi.Color3f, t.ks, idx, active), dr.gather(mi.Color3f, t.kr, idx, active),
                        dr.gather(mi.Float, t.shininess, idx, active))
            if not active or si.shape is None:
                return t.zero_material
            return t.by_id[si.shape.id()]

        def local(self, scene, si, mat, n, v, active):
            """C_amb ka + sum_l vis_l C_l (kd max(0, n.L) + ks max(0, r.v)^n) at si, normal n, towards v."""
            s, t = self.switches, self.tables
            ka, kd, ks, _, shininess = mat
            color = mi.Color3f(0.0)
            if s.ambient:
                color += t.ambient * ka
            if not (s.diffuse or s.specular):
                return color
            for light_pos, light_color in t.lights:
                L = dr.normalize(light_pos - si.p)
                n_dot_l = dr.dot(n, L)
                lit = active & (n_dot_l > 0.0)
                if s.shadows:
                    # Mitsuba's own offset (spawn_ray_to) and any-hit query, not warprt's error bounds.
                    lit &= ~scene.ray_test(si.spawn_ray_to(light_pos), lit)
                term = mi.Color3f(0.0)
                if s.diffuse:
                    term += kd * n_dot_l
                if s.specular:
                    r = 2.0 * n_dot_l * n - L
                    r_dot_v = dr.dot(r, v)
                    term += dr.select(r_dot_v > 0.0, ks * dr.power(dr.maximum(r_dot_v, 0.0), shininess), 0.0)
                color += dr.select(lit, light_color * term, 0.0)
            return color

        @dr.syntax
        def sample(self, scene, sampler, ray, medium=None, active=True):
            t = self.tables
            max_depth = self.switches.max_depth if self.switches.reflection else 1
            ray = mi.Ray3f(ray)
            active = mi.Bool(active)
            weight = mi.Color3f(1.0)
            color = mi.Color3f(0.0)
            depth = mi.UInt32(0)
            while active:
                si = scene.ray_intersect(ray, ray_flags=mi.RayFlags.Minimal | mi.RayFlags.ShadingFrame,
                                         coherent=depth == 0, active=active)
                hit = si.is_valid()
                color = dr.select(active & ~hit, color + weight * t.background, color)
                active &= hit
                # Two-sided surfaces: both normals turned to face the incoming ray, by the geometric side.
                side = dr.select(dr.dot(si.n, ray.d) > 0.0, -1.0, 1.0)
                # Where interpolated vertex normals cancel (normalised zero: NaN), the face normal.
                n = dr.select(dr.isfinite(si.sh_frame.n.x), si.sh_frame.n, si.n) * side
                mat = self.material(si, active)
                color = dr.select(active, color + weight * self.local(scene, si, mat, n, -ray.d, active), color)
                depth += 1
                kr = mat[3]
                active &= (depth < max_depth) & (dr.max(kr) > 0.0)
                weight *= kr
                ray = si.spawn_ray(dr.normalize(ray.d - 2.0 * dr.dot(ray.d, n) * n))
            return color, mi.Bool(True), []

        def aov_names(self):
            return []

        def to_string(self):
            return f"WhittedIntegrator[{self.switches}]"

    mi.register_integrator(INTEGRATOR, lambda props: WhittedIntegrator(props))


class _Tables:
    """Per-scene constants the integrator reads: materials keyed by shape, lights, C_amb, background."""

    def __init__(self, mi, dr, mi_scene, scene, object_of_shape: dict):
        self.jit = dr.is_jit_v(mi.Float)
        self.row_of_object = {}  # scene object index -> table row (its shape's registry index; row 0: a miss)
        lights = [(np.asarray(l.position, np.float64), np.asarray(l.color, np.float64)) for l in scene.lights]
        mats = {sid: scene.materials[scene.objects[i].material] for sid, i in object_of_shape.items()}
        if self.jit:
            # Opaque: kernel inputs rather than literals, so the kernels are not specialised to these
            # values and another scene with as many lights reuses them.
            def opaque(tp, v):
                return dr.opaque(tp, [float(x) for x in v])

            self.lights = [(opaque(mi.Point3f, p), opaque(mi.Color3f, c)) for p, c in lights]
            self.ambient = opaque(mi.Color3f, scene.render.ambient)
            self.background = opaque(mi.Color3f, scene.render.background)
            ids = {}
            for shape in mi_scene.shapes():
                ids[shape.id()] = int(dr.reinterpret_array(mi.UInt32, mi.ShapePtr(shape))[0])
            rows = max(ids.values(), default=0) + 1  # row 0: no shape (a miss)
            table = {k: np.zeros((rows, 3)) for k in ("ka", "kd", "ks", "kr", "kt", "sigma")}
            shininess = np.zeros(rows)
            eta = np.zeros(rows)  # 0: not a dielectric
            for sid, m in mats.items():
                r = ids[sid]
                table["ka"][r], table["kd"][r], table["ks"][r] = m.ka, m.kd, m.ks
                table["kr"][r], shininess[r] = m.reflectivity, m.shininess
                if m.ior is not None:
                    eta[r], table["kt"][r], table["sigma"][r] = m.ior, m.transmittance, m.absorption
                self.row_of_object[object_of_shape[sid]] = r
            for k, v in table.items():
                setattr(self, k, mi.Float(v.astype(np.float32).ravel()))
            self.shininess = mi.Float(shininess.astype(np.float32))
            self.eta = mi.Float(eta.astype(np.float32))
            self.dielectric_rows = {int(r) for r in np.nonzero(eta > 0)[0]}
        else:
            self.lights = [(mi.Point3f(*map(float, p)), mi.Color3f(*map(float, c))) for p, c in lights]
            self.ambient = mi.Color3f(*map(float, scene.render.ambient))
            self.background = mi.Color3f(*map(float, scene.render.background))
            col = lambda v: mi.Color3f(*map(float, v))
            self.by_id = {sid: (col(m.ka), col(m.kd), col(m.ks), col(m.reflectivity), mi.Float(m.shininess))
                          for sid, m in mats.items()}
            self.zero_material = (col((0, 0, 0)),) * 4 + (mi.Float(0.0),)


def _mesh(mi, name: str, vertices: np.ndarray, faces: np.ndarray, normals: np.ndarray | None):
    """A mi.Mesh from world-space float64 arrays (cast to Mitsuba's float32 storage)."""
    mesh = mi.Mesh(name, len(vertices), len(faces), has_vertex_normals=normals is not None)
    params = mi.traverse(mesh)
    # The mesh's own buffer types (JIT arrays, or dynamic arrays in the scalar variants).
    buffer = lambda key, a, dtype: type(params[key])(np.ascontiguousarray(a, dtype).ravel())
    params["vertex_positions"] = buffer("vertex_positions", vertices, np.float32)
    params["faces"] = buffer("faces", faces, np.uint32)
    params.update()
    if normals is not None:
        # Set after the positions: an update that names vertex_positions recomputes the normals.
        params["vertex_normals"] = buffer("vertex_normals", normals, np.float32)
        params.update()
    return mesh


class MitsubaScene:
    """One warprt Scene converted to Mitsuba once (meshes, Embree BVH, tables); renders it with
    any camera and switches. The integrator object is reused, so a repeated render of the same
    configuration hits Dr.Jit's kernel cache instead of compiling again."""

    def __init__(self, scene, smooth: bool = True):
        from warprt.scene import vertex_normals  # the scene's normals, as the scene defines them

        mi, dr = self.mi, self.dr = mitsuba()
        self.scene = scene
        self.smooth = smooth
        shapes, object_of_shape = {}, {}
        for i, obj in enumerate(scene.objects):
            key = f"object_{i:05d}"
            normals = vertex_normals(obj.vertices, obj.faces) if (smooth and obj.smooth) else None
            shapes[key] = _mesh(mi, key, obj.vertices, obj.faces, normals)
            object_of_shape[key] = i
        self.mi_scene = mi.load_dict({"type": "scene", **shapes})
        self.integrator = mi.load_dict({"type": INTEGRATOR})
        self.integrator.tables = _Tables(mi, dr, self.mi_scene, scene, object_of_shape)
        self._sensors = {}
        lo, hi = scene.bounds()
        self._extent = float(max(np.abs(hi - lo).max(), 1e-6))

    def sensor(self, camera, spp: int = 1):
        """Mitsuba's perspective sensor for a warprt Camera: look_at(eye, center, up), vertical fov,
        box-filtered film, stratified sampler without jitter (k*k samples at the stratum centres)."""
        key = (camera, spp)
        if key not in self._sensors:
            mi = self.mi
            eye = np.asarray(camera.eye, np.float64)
            lo, hi = self.scene.bounds()
            reach = float(np.linalg.norm(np.maximum(np.abs(hi - eye), np.abs(lo - eye)))) + self._extent
            self._sensors[key] = mi.load_dict({
                "type": "perspective",
                "fov_axis": "y",
                "fov": float(camera.fovy),
                # warprt's rays start at the eye (d_f only sizes the image plane): clip as little as possible.
                "near_clip": 1e-6 * reach,
                "far_clip": 4.0 * reach,
                "to_world": mi.ScalarTransform4f().look_at(origin=list(map(float, camera.eye)),
                                                          target=list(map(float, camera.center)),
                                                          up=list(map(float, camera.up))),
                "film": {"type": "hdrfilm", "width": int(camera.width), "height": int(camera.height),
                         "rfilter": {"type": "box"}, "pixel_format": "rgb", "component_format": "float32"},
                "sampler": {"type": "stratified", "sample_count": int(spp), "jitter": False},
            })
        return self._sensors[key]

    def render(self, switches: Switches = Switches(), camera=None) -> np.ndarray:
        """Linear RGB float32 (H, W, 3), row 0 at the top."""
        mi = self.mi
        k = math.isqrt(switches.spp)
        if k * k != switches.spp:
            raise ValueError(f"spp must be a square (k*k stratified samples), got {switches.spp}")
        if switches.smooth != self.smooth and any(o.smooth for o in self.scene.objects):
            raise ValueError("this MitsubaScene was built with smooth=%s" % self.smooth)
        camera = camera or self.scene.camera
        if switches.tree:
            from .ray_tree import render_tree

            return render_tree(self, switches, camera).image
        self.integrator.switches = switches
        image = mi.render(self.mi_scene, sensor=self.sensor(camera, switches.spp), integrator=self.integrator,
                          spp=switches.spp, seed=0)
        return np.array(image, dtype=np.float32)[:, :, :3]


_scenes = ObjectCache(size=4)


def mitsuba_scene(scene, smooth: bool = True) -> MitsubaScene:
    """The converted scene, built once per (Scene object, smooth) and kept for the next few calls
    (a comparison at several effect levels converts the scene once)."""
    return _scenes.get((id(scene), bool(smooth)), scene, lambda: MitsubaScene(scene, smooth))


def render_mitsuba(scene, effects=None, disable=()) -> np.ndarray:
    """Render ``scene`` in Mitsuba with the effect set warprt.render(scene, effects=, disable=) uses."""
    from warprt.scene import resolve_effects

    fx = resolve_effects(scene, effects, disable)
    switches = Switches.for_effects(fx, scene.render)
    return mitsuba_scene(scene, switches.smooth).render(switches)
