"""A warprt Scene rendered by Mitsuba 3: the same Whitted model on Mitsuba's own sensor, sampler,
film, Embree intersection and ray spawning, sharing no tracing code with src/warprt.

Model (the seed's Figure 3, as warprt defines it), per colour channel, two-sided surfaces (a
single-sided material's back faces passed through, as glTF culls them; shadow rays still meet them):
    I = C_amb ka + sum_l vis_l C_l (kd max(0, n.L) + ks max(0, r.v)^n) + k_r I(reflected),
vis_l = 0 when n.L <= 0 or the shadow ray is blocked; a miss returns the background; max_depth ray levels.
The lights are Mitsuba's own emitters (point, spot, directional): L, C_l with its spot profile and
1/r^2, and the shadow ray's end come from their sample_direction, not from a copy of warprt's model.
ka, kd and ks at a hit are the material's times its textures (Mitsuba's bilinear bitmap with its wrap
or its checkerboard, at the mesh's own uv) and, for ka and kd, the mesh's vertex colour attribute.
With glass, + F I(reflected) + (1 - F) k_t I(refracted) at a dielectric, each segment inside weighted
by exp(-sigma d): the ray tree of ray_tree.py, level by level, which mi.render cannot branch into.
"""

from __future__ import annotations

import math
import os
import sys
from dataclasses import dataclass

import numpy as np

# Dr.Jit 1.5 needs an LLVM it can drive; Debian 12's libLLVM 15 crashes it ("Cannot select: fminimum").
LLVM_PATH = "/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1"
INTEGRATOR = "warprt_whitted"
ATTRIBUTES = "warprt_attributes"

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
    texture: bool = True  # materials' textures multiply their colours
    vertex_color: bool = True  # meshes' vertex colours multiply ka and kd
    reflection: bool = True  # mirrors (k_r) spawn reflected rays
    refraction: bool = False  # dielectrics (ior) spawn reflected and refracted rays: the ray tree
    absorption: bool = False  # Beer's law inside dielectrics

    @classmethod
    def for_effects(cls, fx, settings) -> "Switches":
        """The switches that match warprt rendering ``settings`` (a RenderSettings) with EffectSet ``fx``."""
        return cls(ambient=fx.ambient, diffuse=fx.diffuse, specular=fx.specular, shadows=fx.shadows,
                   max_depth=settings.max_depth if fx.reflection or fx.refraction else 1,
                   spp=settings.spp if fx.supersampling else 1, smooth=fx.smooth, texture=fx.texture,
                   vertex_color=fx.vertex_color, reflection=fx.reflection, refraction=fx.refraction,
                   absorption=fx.absorption)

    @property
    def tree(self) -> bool:
        """Whether the render needs the ray tree (ray_tree.py) rather than mi.render's single path."""
        return self.refraction or self.absorption


def _register_integrator(mi, dr):
    class WhittedIntegrator(mi.SamplingIntegrator):
        """Whitted ray tracing with Phong shading, Mitsuba's point, spot and directional emitters, hard shadows and mirrors."""

        def __init__(self, props):
            super().__init__(props)
            self.switches = Switches()
            self.tables = None  # _Tables of the scene being rendered, set by MitsubaScene

        def material(self, si, active):
            """(ka, kd, ks, k_r, shininess) at the hit: the shape's material, from tables keyed by the
            shape, times its textures and vertex colours (the shape's Attributes BSDF) where on."""
            t, s = self.tables, self.switches
            if t.jit:
                # A ShapePtr in a JIT variant is the shape's index in Dr.Jit's instance registry.
                idx = dr.reinterpret_array(mi.UInt32, si.shape)
                ka, kd, ks, kr, shininess = (
                    dr.gather(mi.Color3f, t.ka, idx, active), dr.gather(mi.Color3f, t.kd, idx, active),
                    dr.gather(mi.Color3f, t.ks, idx, active), dr.gather(mi.Color3f, t.kr, idx, active),
                    dr.gather(mi.Float, t.shininess, idx, active))
            elif not active or si.shape is None:
                return t.zero_material
            else:  # an area light's own shape has no material: black, as warprt draws it
                ka, kd, ks, kr, shininess = t.by_id.get(si.shape.id(), t.zero_material)
            if t.own_textures and s.texture:
                # A scene file's own BSDFs: Mitsuba's evaluation of the diffuse texture the file gave.
                albedo = si.bsdf().eval_diffuse_reflectance(si, active)
                textured = dr.gather(mi.Bool, t.textured, idx, active) if t.jit else t.textured_ids.get(si.shape.id(), False)
                ka, kd = dr.select(textured, ka * albedo, ka), dr.select(textured, kd * albedo, kd)
            if t.attributes and s.texture:
                bsdf = si.bsdf()
                ka = ka * bsdf.eval_attribute_3("ka", si, active)
                kd = kd * bsdf.eval_attribute_3("kd", si, active)
                ks = ks * bsdf.eval_attribute_3("ks", si, active)
            if t.attributes and s.vertex_color:
                color = si.bsdf().eval_attribute_3("vertex_color", si, active)
                ka, kd = ka * color, kd * color
            return ka, kd, ks, kr, shininess

        def local(self, scene, si, mat, n, v, active):
            """C_amb ka + sum_l vis_l C_l (kd max(0, n.L) + ks max(0, r.v)^n) at si, normal n, towards v."""
            s, t = self.switches, self.tables
            ka, kd, ks, _, shininess = mat
            color = mi.Color3f(0.0)
            if t.area:
                color += self.emitted(scene, si, active)
            if s.ambient:
                color += t.ambient * ka
            if not (s.diffuse or s.specular):
                return color
            for emitter, unscaled in t.lights:
                # Mitsuba's light model: the direction to the light, its distance and C_l times the
                # spot's profile (its falloff_curve) over r^2; a delta light ignores the sample.
                ds, light_color = emitter.sample_direction(si, mi.Point2f(0.5, 0.5), active)
                if unscaled:
                    # warprt's falloff "none" (the seed's model): Mitsuba's weight times r^2, r its ds.dist.
                    light_color = light_color * dr.square(ds.dist)
                # The emitter's sampled point: for a directional light, beyond the scene's bounding sphere.
                term, lit = self.phong(scene, si, ds.d, ds.p, active, kd, ks, shininess, n, v)
                color += dr.select(lit, light_color * term, 0.0)
            for emitter, shape, uv in zip(t.area, t.area_shapes, t.area_uv):
                color += self.area_light(scene, si, emitter, shape, uv, kd, ks, shininess, n, v, active)
            return color

        def phong(self, scene, si, L, target, lit, kd, ks, shininess, n, v):
            """(kd n.L + ks max(0, r.v)^n, where it is lit): the Phong terms at si of light from direction L
            and point ``target``, lit where ``lit``, n.L > 0 and, with shadows, Mitsuba's own offset
            (spawn_ray_to) and any-hit query find nothing on the way."""
            s = self.switches
            n_dot_l = dr.dot(n, L)
            lit = lit & (n_dot_l > 0.0)
            if s.shadows:
                lit &= ~scene.ray_test(si.spawn_ray_to(target), lit)
            term = mi.Color3f(0.0)
            if s.diffuse:
                term += kd * n_dot_l
            if s.specular:
                r = 2.0 * n_dot_l * n - L
                r_dot_v = dr.dot(r, v)
                term += dr.select(r_dot_v > 0.0, ks * dr.power(dr.maximum(r_dot_v, 0.0), shininess), 0.0)
            return term, lit

        def emitted(self, scene, si, active):
            """The radiance of an area emitter's surface seen at si: Mitsuba's own eval (one-sided: 0
            where si.wi is behind the emitting side), 0 on shapes that emit nothing."""
            if self.tables.jit:
                return si.emitter(scene, active).eval(si, active)
            emitter = si.emitter(scene, active) if active else None
            return emitter.eval(si, active) if emitter is not None else mi.Color3f(0.0)

        def area_light(self, scene, si, emitter, shape, uv, kd, ks, shininess, n, v, active):
            """One area light at si: warprt's fixed sample points ``uv`` of the unit square (the k x k cell
            centres for a shape, the Fibonacci lattice for a mesh: sample_coordinates) handed to Mitsuba's
            own emitter.sample_direction, which places each on the shape as its
            sample_position does and weighs it L_e |cos'| A / r^2 (0 from behind: one-sided); each point,
            weight / k^2, lights the Phong terms as a point light would, through one shadow ray."""
            t = self.tables
            color = mi.Color3f(0.0)
            sphere = shape.shape_type() == mi.ShapeType.Sphere
            if sphere:  # Mitsuba's sphere samples directions by its cone: its sample_position is warprt's rule
                radiance, area = mi.Color3f(mi.traverse(emitter)["radiance.value"]), shape.surface_area()
            for a, b in uv:
                if sphere:
                    ps = shape.sample_position(si.time, mi.Point2f(a, b), active)
                    to_p = ps.p - si.p
                    dist2 = dr.squared_norm(to_p)
                    L = to_p / dr.sqrt(dist2)
                    cos_e = -dr.dot(ps.n, L)
                    weight, target, ok = radiance * (cos_e * area / dist2), ps.p, cos_e > 0.0
                else:
                    ds, weight = emitter.sample_direction(si, mi.Point2f(a, b), active)
                    L, target, ok = ds.d, ds.p, ds.pdf > 0.0
                term, lit = self.phong(scene, si, L, target, active & ok, kd, ks, shininess, n, v)
                color += dr.select(lit, weight * term * t.area_share, 0.0)
            return color

        def intersect(self, scene, ray, flags, coherent, active):
            """scene.ray_intersect, continued past the back faces of single-sided materials (glTF's
            back-face culling: si.n, the winding's normal, facing away from the ray's origin) by
            Mitsuba's own spawn_ray, on along the same direction to the next surface or a miss."""
            si = scene.ray_intersect(ray, ray_flags=flags, coherent=coherent, active=active)
            if not self.tables.culling:
                return si
            return self.skip_culled(scene, si, ray.d, flags, active & self.culled(si, ray.d))

        @dr.syntax
        def skip_culled(self, scene, si, d, flags, skip):
            while skip:
                si = dr.select(skip, scene.ray_intersect(si.spawn_ray(d), ray_flags=flags, coherent=False, active=skip), si)
                skip &= self.culled(si, d)
            return si

        def culled(self, si, d):
            """Whether direction d passes through the hit si: a single-sided material seen from behind."""
            t = self.tables
            if t.jit:
                single = dr.gather(mi.Bool, t.cull, dr.reinterpret_array(mi.UInt32, si.shape), si.is_valid())
            else:
                single = si.is_valid() and si.shape is not None and si.shape.id() in t.culled_ids
            return single & (dr.dot(si.n, d) > 0.0)

        @dr.syntax
        def sample(self, scene, sampler, ray, medium=None, active=True):
            ray = mi.Ray3f(ray)
            active = mi.Bool(active)
            weight = mi.Color3f(1.0)
            color = mi.Color3f(0.0)
            depth = mi.UInt32(0)
            while active:
                ray, color, weight, active = self.level(scene, ray, depth, color, weight, active)
                depth += 1
            return color, mi.Bool(True), []

        def max_depth(self) -> int:
            """The ray levels sample() follows: the switches' max_depth with mirrors, else the camera rays'."""
            return self.switches.max_depth if self.switches.reflection else 1

        def level(self, scene, ray, depth, color, weight, active, detach: bool = False):
            """One ray level of sample(): the hit of ``ray`` (level ``depth``), its background or local colour
            times ``weight`` added to ``color``, and the mirror ray it spawns while k_r > 0 and max_depth
            allows. Returns (ray, color, weight, active) for the next level; straight-line code, so that a
            caller may also unroll the levels in Python (Mitsuba's AD then needs no symbolic loop). With
            ``detach`` (RayFlags.DetachShape), the hits do not follow the shapes' parameters under AD."""
            t = self.tables
            # Without the UV flag, si.uv holds the triangle's barycentrics, not the mesh's texture coordinates.
            flags = mi.RayFlags.Minimal | mi.RayFlags.ShadingFrame
            if t.attributes or t.own_textures:
                flags = flags | mi.RayFlags.UV
            if detach:
                flags = flags | mi.RayFlags.DetachShape
            si = self.intersect(scene, ray, flags, depth == 0, active)
            hit = si.is_valid()
            color = dr.select(active & ~hit, color + weight * t.background, color)
            active &= hit
            # Two-sided surfaces: both normals turned to face the incoming ray, by the geometric side.
            side = dr.select(dr.dot(si.n, ray.d) > 0.0, -1.0, 1.0)
            # Where interpolated vertex normals cancel (normalised zero: NaN), the face normal.
            n = dr.select(dr.isfinite(si.sh_frame.n.x), si.sh_frame.n, si.n) * side
            mat = self.material(si, active)
            color = dr.select(active, color + weight * self.local(scene, si, mat, n, -ray.d, active), color)
            kr = mat[3]
            active &= (depth + 1 < self.max_depth()) & (dr.max(kr) > 0.0)
            weight *= kr
            return si.spawn_ray(dr.normalize(ray.d - 2.0 * dr.dot(ray.d, n) * n)), color, weight, active

        def aov_names(self):
            return []

        def to_string(self):
            return f"WhittedIntegrator[{self.switches}]"

    mi.register_integrator(INTEGRATOR, lambda props: WhittedIntegrator(props))

    class Attributes(mi.BSDF):
        """Not a scattering model: what one shape's material and mesh add to its Phong colours, read
        at a hit by eval_attribute_3: "ka", "kd", "ks" their texture's value (1 where untextured),
        "vertex_color" the mesh's colour attribute (1 where it has none)."""

        def __init__(self, props):
            mi.BSDF.__init__(self, props)
            self.textures = {k: props.get(k) for k in ("ka", "kd", "ks")}
            self.colored = bool(props.get("colored", False))
            self.m_flags = mi.BSDFFlags.DiffuseReflection | mi.BSDFFlags.FrontSide

        def eval_attribute_3(self, name, si, active=True):
            if name == "vertex_color":
                return si.shape.eval_attribute_3("vertex_color", si, active) if self.colored else mi.Color3f(1.0)
            return self.textures[name].eval(si, active)

        def sample(self, ctx, si, sample1, sample2, active=True):  # the integrator never scatters
            # Zeros, not uninitialised: a symbolic call of another integrator (Mitsuba's direct) traces every
            # live BSDF instance, these too (it failed after a test had built one: "callable returned an empty array").
            return dr.zeros(mi.BSDFSample3f), mi.Color3f(0.0)

        def eval(self, ctx, si, wo, active=True):
            return mi.Color3f(0.0)

        def pdf(self, ctx, si, wo, active=True):
            return mi.Float(0.0)

        def eval_pdf(self, ctx, si, wo, active=True):
            return mi.Color3f(0.0), mi.Float(0.0)

        def traverse(self, callback):
            pass

        def to_string(self):
            return "Attributes[]"

    mi.register_bsdf(ATTRIBUTES, lambda props: Attributes(props))


def _texture(mi, t):
    """A warprt Texture as Mitsuba's: a bilinear bitmap with its wrap mode of the same linear texels (row 0 at
    v = 0, as Mitsuba's bitmaps are), or its checkerboard, whose 2 x 2 checks per unit uv become one
    per unit by halving the uv map; constant 1 where there is none."""
    if t is None:
        return mi.load_dict({"type": "rgb", "value": [1.0, 1.0, 1.0]})
    a = t.uv_transform
    to_uv = mi.ScalarTransform4f([[a[0], a[1], 0.0, a[2]], [a[3], a[4], 0.0, a[5]], [0, 0, 1, 0], [0, 0, 0, 1]])
    if t.checker is not None:
        return mi.load_dict({"type": "checkerboard", "to_uv": mi.ScalarTransform4f().scale([0.5, 0.5, 1.0]) @ to_uv,
                             "color0": {"type": "rgb", "value": list(map(float, t.checker[0]))},
                             "color1": {"type": "rgb", "value": list(map(float, t.checker[1]))}})
    # Mitsuba's bitmap has one wrap mode for both axes (its repeat, clamp and mirror are OpenGL's, as Warp's are).
    if t.wrap[0] != t.wrap[1]:
        raise ValueError(f"{t.source}: wrap {t.wrap[0]} along u and {t.wrap[1]} along v: Mitsuba's bitmap has one "
                         "wrap mode for both axes")
    return mi.load_dict({"type": "bitmap", "bitmap": mi.Bitmap(np.array(t.image, np.float32)),  # a writable copy
                         "filter_type": "bilinear", "wrap_mode": t.wrap[0], "raw": True, "to_uv": to_uv})


class _Tables:
    """Per-scene constants the integrator reads: materials keyed by shape, lights, C_amb, background."""

    def __init__(self, mi, dr, mi_scene, scene, object_of_shape: dict, attributes: bool, emitters: list,
                 own_textures: bool = False, area: list = ()):
        self.jit = dr.is_jit_v(mi.Float)
        # The area lights' emitters, sampled at the cell centres of a k x k grid, each 1 / k^2 of the light.
        self.area_shapes = [shape for shape, _ in area]  # kept alive: an emitter points to its shape
        self.area = [emitter for _, emitter in area]
        k = math.isqrt(scene.render.light_samples) if self.area else 0
        # Per area light, warprt's own points of the unit square (scene.area_lights' order, as ``area``).
        from warprt.scene import sample_coordinates

        self.area_uv = ([list(zip(*(c.tolist() for c in sample_coordinates(light, k)))) for light in scene.area_lights]
                        if self.area else [])
        self.area_share = 1.0 / (k * k) if self.area else 0.0
        self.attributes = attributes  # whether the shapes carry Attributes BSDFs (textures, vertex colours)
        # Whether textured materials take their texture from the shape's own Mitsuba BSDF (a scene file's).
        self.own_textures = own_textures
        textured_ids = {sid for sid, i in object_of_shape.items() if scene.materials[scene.objects[i].material].textures}
        self.textured_ids = {sid: True for sid in textured_ids}
        self.row_of_object = {}  # scene object index -> table row (its shape's registry index; row 0: a miss)
        # Each light as Mitsuba's emitter (in the scene, so a directional one knows its bounds), and
        # whether its falloff is warprt's "none", which Mitsuba's point and spot emitters do not have
        # (a directional one's weight is its irradiance, with no distance in it).
        self.lights = [(emitter, light.falloff == "none" and light.type != "directional")
                       for emitter, light in zip(emitters, whitted_lights(scene))]
        mats = {sid: scene.materials[scene.objects[i].material] for sid, i in object_of_shape.items()}
        # Whether some material is single-sided: only then are hits tested for culling (as warprt's variants).
        self.culling = any(not m.double_sided for m in mats.values())
        self.culled_ids = {sid for sid, m in mats.items() if not m.double_sided}
        if self.jit:
            # Opaque: kernel inputs rather than literals, so the kernels are not specialised to these
            # values and another scene with as many lights reuses them.
            def opaque(tp, v):
                return dr.opaque(tp, [float(x) for x in v])

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
            cull = np.zeros(rows, bool)
            cull[[ids[sid] for sid in self.culled_ids]] = True
            self.cull = mi.Bool(cull)
            textured = np.zeros(rows, bool)
            textured[[ids[sid] for sid in textured_ids]] = True
            self.textured = mi.Bool(textured)
        else:
            self.ambient = mi.Color3f(*map(float, scene.render.ambient))
            self.background = mi.Color3f(*map(float, scene.render.background))
            col = lambda v: mi.Color3f(*map(float, v))
            self.by_id = {sid: (col(m.ka), col(m.kd), col(m.ks), col(m.reflectivity), mi.Float(m.shininess))
                          for sid, m in mats.items()}
            self.zero_material = (col((0, 0, 0)),) * 4 + (mi.Float(0.0),)


def _emitter(mi, light):
    """A warprt Light as Mitsuba's own emitter: ``point`` (position, intensity), ``spot`` (intensity,
    cutoff_angle and beam_width in degrees, to_world looking along its direction) or ``directional``
    (direction, irradiance); C_l is the intensity or irradiance."""
    color = {"type": "rgb", "value": [float(c) for c in light.color]}
    if light.type == "directional":
        return mi.load_dict({"type": "directional", "direction": [float(x) for x in light.direction], "irradiance": color})
    p = np.asarray(light.position, np.float64)
    if light.type == "point":
        return mi.load_dict({"type": "point", "position": p.tolist(), "intensity": color})
    d = np.asarray(light.direction, np.float64)
    up = np.eye(3)[int(np.argmin(np.abs(d)))]  # any axis not along d: the profile is symmetric about it
    return mi.load_dict({"type": "spot", "intensity": color, "cutoff_angle": float(light.cutoff_angle),
                         "beam_width": float(light.beam),
                         "to_world": mi.ScalarTransform4f().look_at(origin=p.tolist(), target=(p + d).tolist(),
                                                                    up=up.tolist())})


def _area_emitter(mi, light):
    """Mitsuba's ``area`` emitter of a warprt area light's radiance (one-sided, as warprt's)."""
    return mi.load_dict({"type": "area", "radiance": {"type": "rgb", "value": [float(c) for c in light.radiance]}})


def _shape_light(mi, light):
    """A rectangle or disk light as Mitsuba's own analytic shape with an area emitter: to_world maps its
    local [-1, 1]^2 square (the unit disk) onto center + x u + y v, emitting along u x v."""
    from warprt.scene import shape_frame

    if light.shape == "sphere":
        return mi.load_dict({"type": "sphere", "center": [float(x) for x in (light.center or (0.0, 0.0, 0.0))],
                             "radius": float(light.radius), "emitter": _area_emitter(mi, light)})
    c, u, v = shape_frame(light)
    m = np.eye(4)
    m[:3, 0], m[:3, 1], m[:3, 2], m[:3, 3] = u, v, np.cross(u, v) / np.linalg.norm(np.cross(u, v)), c
    return mi.load_dict({"type": light.shape, "to_world": mi.ScalarTransform4f(m), "emitter": _area_emitter(mi, light)})


def _area_samplers(mi, scene, shapes_by_key: dict) -> list:
    """Per area light (scene.area_lights' order), (shape, emitter): the emitter whose sample_direction places its points: a
    shape light's own analytic shape (shapes_by_key["area_j"]), and for an object light a mesh of the
    object's triangles as warprt reads them (Mitsuba's mesh sampling: a face by area, then the
    triangle), outside the scene, which draws the object with its own emitter."""
    samplers = []
    for j, light in enumerate(scene.area_lights):
        if light.shape is not None:
            shape = shapes_by_key[f"area_{j:03d}"]
            samplers.append((shape, shape.emitter()))
            continue
        objs = [o for o in scene.objects if o.name == light.object]
        vertices = np.concatenate([o.vertices for o in objs])
        offsets = np.cumsum([0] + [len(o.vertices) for o in objs])[:-1]
        faces = np.concatenate([o.faces + off for o, off in zip(objs, offsets)])
        mesh = _mesh(mi, f"sampler_{j:03d}", vertices, faces, None, emitter=_area_emitter(mi, light))
        samplers.append((mesh, mesh.emitter()))  # the mesh kept: its emitter holds only a pointer to it
    return samplers


def _mesh(mi, name: str, vertices: np.ndarray, faces: np.ndarray, normals: np.ndarray | None,
          uv: np.ndarray | None = None, colors: np.ndarray | None = None, bsdf=None, emitter=None):
    """A mi.Mesh from world-space float64 arrays (cast to Mitsuba's float32 storage), with its texture
    coordinates and its vertex colours as the attribute "vertex_color"; ``emitter``: an area emitter on it."""
    props = mi.Properties()
    if bsdf is not None:
        props["bsdf"] = bsdf
    if emitter is not None:
        props["emitter"] = emitter
    mesh = mi.Mesh(name, len(vertices), len(faces), props=props, has_vertex_normals=normals is not None,
                   has_vertex_texcoords=uv is not None)
    params = mi.traverse(mesh)
    # The mesh's own buffer types (JIT arrays, or dynamic arrays in the scalar variants).
    buffer = lambda key, a, dtype: type(params[key])(np.ascontiguousarray(a, dtype).ravel())
    params["vertex_positions"] = buffer("vertex_positions", vertices, np.float32)
    params["faces"] = buffer("faces", faces, np.uint32)
    if uv is not None:
        params["vertex_texcoords"] = buffer("vertex_texcoords", uv, np.float32)
    params.update()
    if normals is not None:
        # Set after the positions: an update that names vertex_positions recomputes the normals.
        params["vertex_normals"] = buffer("vertex_normals", normals, np.float32)
        params.update()
    if colors is not None:
        mesh.add_attribute("vertex_color", 3, type(params["vertex_positions"])(np.ascontiguousarray(colors, np.float32).ravel()))
    return mesh


def whitted_lights(scene) -> list:
    """The scene's point, spot and directional lights (its area lights are integrated apart: area_light)."""
    return [light for light in scene.lights if light.type not in ("area", "environment")]


def refuse_environment(scene):
    """A SceneError naming ``lights`` where the scene has an environment light, which this reference has not."""
    if any(light.type == "environment" for light in scene.lights):
        from warprt import SceneError

        raise SceneError(scene.source, "lights", "an environment light is not in the Whitted reference: Mitsuba's "
                                                 "direct integrator on the scene's XML file is (reference/mitsuba_direct.py)")


class MitsubaScene:
    """One warprt Scene converted to Mitsuba once (meshes, Embree BVH, tables); renders it with
    any camera and switches. The integrator object is reused, so a repeated render of the same
    configuration hits Dr.Jit's kernel cache instead of compiling again."""

    def __init__(self, scene, smooth: bool = True):
        from warprt.scene import vertex_normals  # the scene's normals, as the scene defines them

        refuse_environment(scene)
        mi, dr = self.mi, self.dr = mitsuba()
        self.scene = scene
        self.smooth = smooth
        # Textures and vertex colours ride on a per-shape BSDF, only where the scene has any.
        attributes = any(m.textures for m in scene.materials.values()) or any(
            getattr(o, "colors", None) is not None for o in scene.objects)
        shapes, object_of_shape, textures = {}, {}, {}
        for i, obj in enumerate(scene.objects):
            key = f"object_{i:05d}"
            normals = None
            if smooth and obj.smooth:  # the scene's own normals (the file's, crease-split) where it has them
                normals = obj.normals if getattr(obj, "normals", None) is not None else vertex_normals(obj.vertices, obj.faces)
            uv, colors, bsdf = getattr(obj, "uv", None), getattr(obj, "colors", None), None
            if attributes:
                m = scene.materials[obj.material]
                if m.textures and uv is None:
                    uv = np.zeros((len(obj.vertices), 2))  # as warprt samples a mesh without uv: at (0, 0)
                maps = {}
                for k in ("ka", "kd", "ks"):
                    t = getattr(m, f"{k}_texture")
                    if id(t) not in textures:  # one Mitsuba texture per warprt one
                        textures[id(t)] = _texture(mi, t)
                    maps[k] = textures[id(t)]
                bsdf = mi.load_dict({"type": ATTRIBUTES, "colored": colors is not None, **maps})
            light = next((l for l in scene.area_lights if l.object is not None and l.object == obj.name), None)
            shapes[key] = _mesh(mi, key, obj.vertices, obj.faces, normals, uv, colors, bsdf,
                                emitter=_area_emitter(mi, light) if light is not None else None)
            object_of_shape[key] = i
        for j, light in enumerate(scene.area_lights):
            if light.shape is not None:
                shapes[f"area_{j:03d}"] = _shape_light(mi, light)
        emitters = [_emitter(mi, light) for light in whitted_lights(scene)]
        self.mi_scene = mi.load_dict({"type": "scene", **shapes,
                                      **{f"light_{i:03d}": e for i, e in enumerate(emitters)}})
        self.integrator = mi.load_dict({"type": INTEGRATOR})
        self.integrator.tables = _Tables(mi, dr, self.mi_scene, scene, object_of_shape, attributes,
                                           emitters, area=_area_samplers(mi, scene, shapes))
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
        if switches.tree and self.scene.area_lights:
            from warprt import SceneError

            raise SceneError(self.scene.source, "lights", "the reference's ray tree (glass) does not take area "
                                                          "lights yet")
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


class MitsubaFileScene(MitsubaScene):
    """The scene Mitsuba itself loads from a Mitsuba scene file (its shapes, transforms, analytic spheres,
    its own textures), rendered with the same integrator: the materials and lights are warprt's reading
    of the file (``scene``), matched to the shapes in the order the reader reads them, and the camera is
    the file's sensor (to_world, Mitsuba's x_fov) wherever ``scene``'s camera is the reader's reading of
    it (not changed by overrides such as --width)."""

    def __init__(self, scene, path, smooth: bool = True):
        from warprt.scene import load_mitsuba_file, mitsuba_camera, reads_mitsuba_light, reads_mitsuba_shape

        refuse_environment(scene)  # an envmap or constant emitter: the file's light this integrator has not
        mi, dr = self.mi, self.dr = mitsuba()
        self.scene, self.smooth = scene, smooth
        self.mi_scene = load_mitsuba_file(path)
        self.camera = mitsuba_camera(self.mi_scene, str(path))
        object_of_shape, k = {}, 0
        for j, shape in enumerate(self.mi_scene.shapes()):
            # scene.objects[k] is the k-th shape the reader reads; the rest (skipped, warned) keep no material.
            key = f"object_{k:05d}" if reads_mitsuba_shape(shape) else f"unread_{j:05d}"
            shape.set_id(key)
            if key.startswith("object_"):
                object_of_shape[key], k = k, k + 1
        if k != len(scene.objects):
            raise ValueError(f"{path}: Mitsuba loads {k} shapes warprt reads, the scene has {len(scene.objects)} objects")
        self.integrator = mi.load_dict({"type": INTEGRATOR})
        own = any(m.textures for m in scene.materials.values())
        # The file's own point, spot and directional emitters, in the order the reader reads them into
        # scene.lights (its area lights follow them; other emitters are not lights).
        emitters = [e for e in self.mi_scene.emitters() if reads_mitsuba_light(e)]
        if len(emitters) != len(whitted_lights(scene)):
            raise ValueError(f"{path}: Mitsuba loads {len(emitters)} Whitted lights, the scene has {len(whitted_lights(scene))}")
        self.integrator.tables = _Tables(mi, dr, self.mi_scene, scene, object_of_shape, False, emitters,
                                         own_textures=own, area=_area_samplers(mi, scene, {}))
        self._sensors = {}
        lo, hi = scene.bounds()
        self._extent = float(max(np.abs(hi - lo).max(), 1e-6))

    def sensor(self, camera, spp: int = 1):
        """For the file's own camera, the file's sensor as Mitsuba reads it (to_world, x_fov, film size)
        with the reference's sampler, filter and clip planes; any other camera as MitsubaScene's."""
        if camera != self.camera:
            return super().sensor(camera, spp)
        key = ("file", spp)
        if key not in self._sensors:
            mi = self.mi
            p = mi.traverse(self.mi_scene.sensors()[0])
            base = super().sensor(camera, spp)  # the clip planes warprt's rays need
            self._sensors[key] = mi.load_dict({
                "type": "perspective", "fov_axis": "x", "fov": float(np.ravel(np.array(p["x_fov"]))[0]),
                "near_clip": base.near_clip(), "far_clip": base.far_clip(),
                "to_world": mi.ScalarTransform4f(np.array(p["to_world"].matrix, np.float64).reshape(4, 4)),
                "film": {"type": "hdrfilm", "width": int(camera.width), "height": int(camera.height),
                         "rfilter": {"type": "box"}, "pixel_format": "rgb", "component_format": "float32"},
                "sampler": {"type": "stratified", "sample_count": int(spp), "jitter": False},
            })
        return self._sensors[key]

    def render(self, switches: Switches = Switches(), camera=None) -> np.ndarray:
        # Mitsuba's own normals, whatever the smooth switch (a file's shapes have no flat variant here).
        return super().render(Switches(**{**switches.__dict__, "smooth": self.smooth}), camera)


_scenes = None  # an ObjectCache, made on first use: a script that only renders (whitted_integrator) need not import warprt


def mitsuba_scene(scene, smooth: bool = True) -> MitsubaScene:
    """The converted scene, built once per (Scene object, smooth) and kept for the next few calls
    (a comparison at several effect levels converts the scene once)."""
    global _scenes
    if _scenes is None:
        from warprt.scene import ObjectCache

        _scenes = ObjectCache(size=4)
    if str(scene.source).lower().endswith(".xml"):  # a Mitsuba scene file: the scene Mitsuba loads from it
        return _scenes.get((id(scene), bool(smooth)), scene, lambda: MitsubaFileScene(scene, scene.source, smooth))
    return _scenes.get((id(scene), bool(smooth)), scene, lambda: MitsubaScene(scene, smooth))


def whitted_integrator(mi_scene, scene, object_of_shape: dict, switches: Switches = Switches()):
    """The Whitted integrator for a Mitsuba scene a script built itself (its meshes read by Mitsuba's own
    shape plugins, as a Mitsuba user's script does): ``scene`` gives lights, render.ambient,
    render.background and materials as a warprt Scene names them, ``object_of_shape`` each shape's id
    -> its index in scene.objects, whose .material names its material. No textures or vertex colours."""
    mi, dr = mitsuba()
    integrator = mi.load_dict({"type": INTEGRATOR})
    # The script's emitters are its lights, in the order scene.lights lists them.
    integrator.tables = _Tables(mi, dr, mi_scene, scene, object_of_shape, False, list(mi_scene.emitters()))
    integrator.switches = switches
    return integrator


def render_mitsuba(scene, effects=None, disable=()) -> np.ndarray:
    """Render ``scene`` in Mitsuba with the effect set warprt.render(scene, effects=, disable=) uses."""
    from warprt.scene import resolve_effects

    fx = resolve_effects(scene, effects, disable)
    switches = Switches.for_effects(fx, scene.render)
    return mitsuba_scene(scene, switches.smooth).render(switches)
