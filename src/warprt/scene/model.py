"""The scene: dataclasses that mirror the TOML file one to one. Everything is float64 here;
geometry becomes float32 only when it is handed to the BVH (warprt.geometry)."""

from __future__ import annotations

from dataclasses import dataclass, field, fields, replace

import numpy as np

from ..errors import SceneError, show
from . import shapes
from .placement import shape_fields
from .toml_fields import TableReader, plain


def _as_floats(owner, name: str, v, scalar_ok: bool = False) -> tuple:
    """A vector field as a tuple of floats, whatever sequence gave it (a list, a tuple, a NumPy array):
    the dataclasses are compared and hashed as cache keys. Its length and range are validate.py's."""
    if scalar_ok and isinstance(v, (int, float, np.integer, np.floating)) and not isinstance(v, (bool, np.bool_)):
        return (float(v),) * 3
    try:
        items = list(v)
        if any(isinstance(x, (bool, np.bool_, str, bytes)) for x in items):
            raise TypeError
        return tuple(float(x) for x in items)
    except (TypeError, ValueError):
        raise SceneError(type(owner).__name__, name, f"expected a list of 3 numbers, got {show(v)}") from None


def _as_int(owner, name: str, v):
    """A NumPy integer as int (the stats are JSON); other values are left for validate.py to refuse."""
    return int(v) if isinstance(v, np.integer) else v


def _convert(owner, vectors=(), ints=(), scalar_ok=()):
    for f in fields(owner):
        v = getattr(owner, f.name)
        if f.name in vectors and v is not None:
            object.__setattr__(owner, f.name, _as_floats(owner, f.name, v, f.name in scalar_ok))
        elif f.name in ints:
            object.__setattr__(owner, f.name, _as_int(owner, f.name, v))
from .texture import Texture


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

    def __post_init__(self):
        _convert(self, vectors=("eye", "center", "up"), ints=("width", "height"))


@dataclass(frozen=True)
class RenderSettings:
    ambient: tuple = (0.1, 0.1, 0.1)  # C_amb
    background: tuple = (0.0, 0.0, 0.0)
    max_depth: int = 3  # ray levels: 1 = primary only
    shadows: bool = True
    spp: int = 1  # k*k stratified samples per pixel
    effects: tuple | None = None  # None: every effect the scene calls for
    light_samples: int = 16  # k*k stratified points on each area light, one shadow ray each
    # > 0: Whitted's adaptive supersampling (image/adaptive.py): each pixel's centre traced, and the spp samples
    # only in pixels whose 3 x 3 neighbourhood of centres differs by more than this (a colour channel's step)
    adaptive: float = 0.0
    # "samples": each point a point light; "analytic": a polygon's (rectangle, mesh) or an unclipped sphere's
    # unshadowed diffuse term in closed form, times the points' ratio estimate of its visibility (kernels/shading.py)
    area_estimator: str = "samples"
    light_spread: bool = False  # with spp > 1: each pixel sample takes its own share of the light's points

    def __post_init__(self):
        _convert(self, vectors=("ambient", "background"), ints=("max_depth", "spp", "light_samples"))
        if self.effects is not None and not isinstance(self.effects, tuple):
            if isinstance(self.effects, str):
                raise SceneError("RenderSettings", "effects", f"expected a list of effect names, got {show(self.effects)}")
            object.__setattr__(self, "effects", tuple(self.effects))


LIGHT_TYPES = ("point", "spot", "directional", "area", "environment")
AREA_ESTIMATORS = ("samples", "analytic")  # render.area_estimator
FALLOFFS = ("none", "inverse_square")
AREA_SHAPES = ("rectangle", "disk", "sphere")  # an area light's own shape; else it names an object (Light.object)


@dataclass(frozen=True)
class Light:
    """A Whitted light: point (position), spot (position, direction, cone) or directional (direction
    only), of colour C_l: radiant intensity for point and spot, irradiance for directional. A spot's
    profile is Mitsuba's ``spot``: 1 within beam_width of its axis, falling linearly in angle to 0 at
    cutoff_angle; falloff "inverse_square" divides C_l by the squared distance, "none" (the seed's
    model) does not."""

    position: tuple | None = None  # required for point and spot, None for directional
    color: tuple = (1.0, 1.0, 1.0)  # C_l
    type: str = "point"  # LIGHT_TYPES
    direction: tuple | None = None  # unit vector the light travels along: spot axis, sun direction
    cutoff_angle: float = 20.0  # degrees, spot only (Mitsuba's default)
    beam_width: float | None = None  # degrees, spot only; None: 3/4 of cutoff_angle (Mitsuba's default)
    falloff: str = "none"  # FALLOFFS; a directional light has none, whatever it says (irradiance)
    name: str = ""  # the author's name for a light read from a file, "" otherwise
    # An area light (Mitsuba's ``area`` emitter): radiance L_e leaving one side of a surface, the side
    # its normal points to; the surface is its own ``shape`` (AREA_SHAPES) or the triangles of the
    # objects named ``object``. A rectangle is center +- u +- v (u and v its half-edges, as the columns
    # of Mitsuba's rectangle to_world; normal u x v), or a normal and size = (width, height) around
    # center; a disk has center, normal, radius.
    radiance: tuple | None = None  # L_e, area lights only
    shape: str | None = None
    object: str | None = None
    center: tuple | None = None
    normal: tuple | None = None
    u: tuple | None = None
    v: tuple | None = None
    size: tuple | None = None  # rectangle: (width, height) with normal
    radius: float | None = None  # disk
    # An environment light (Mitsuba's ``envmap``, or its ``constant`` given a radiance): radiance from every
    # direction at infinity, an equirectangular ``image`` (linear RGB; row 0 at v = 0, as textures keep it) or
    # a constant ``radiance``, times ``scale``, turned by ``rotate`` (degrees about x, then y, then z, as an
    # object's rotate: Mitsuba's to_world). Seen by the rays that meet nothing; lights every point.
    image: Texture | None = None
    scale: float | None = None  # environment only; None: 1
    rotate: tuple | None = None  # environment only; None: no rotation

    def __post_init__(self):
        _convert(self, vectors=("position", "color", "direction", "radiance", "center", "normal", "u", "v", "rotate"))
        if self.type == "environment":
            if self.scale is None:
                object.__setattr__(self, "scale", 1.0)
            if self.rotate is None:
                object.__setattr__(self, "rotate", (0.0, 0.0, 0.0))
        if self.size is not None and not isinstance(self.size, (tuple, str)):
            v = self.size
            scalar = isinstance(v, (int, float, np.integer, np.floating)) and not isinstance(v, (bool, np.bool_))
            object.__setattr__(self, "size", (float(v),) * 2 if scalar else _as_floats(self, "size", v))
        # Said once here for every reader (TOML target, glTF node -Z, Mitsuba to_world): a unit
        # direction. A zero or non-finite one is left for validate.py to name.
        d = self.direction
        if d is not None and len(d) == 3:
            norm = float(np.linalg.norm(np.asarray(d, np.float64)))
            if np.isfinite(norm) and norm > 0.0:
                object.__setattr__(self, "direction", tuple(float(x) / norm for x in d))

    @property
    def beam(self) -> float:
        """beam_width in degrees, its default resolved."""
        return 0.75 * self.cutoff_angle if self.beam_width is None else self.beam_width

    @property
    def area(self) -> bool:
        return self.type == "area"

    @property
    def environment(self) -> bool:
        return self.type == "environment"

    @property
    def seed_point(self) -> bool:
        """Whether this is the seed's light: a point with no falloff (the kernels' fast path)."""
        return self.type == "point" and self.falloff == "none"


@dataclass(frozen=True)
class Material:
    """Phong coefficients ka, kd, ks, the exponent n (shininess) and the mirror weight k_r. A colour
    with a texture is the texture's value times the coefficient (glTF's factor times texture), and
    an object's vertex colours multiply ka and kd. With an index of refraction, a dielectric: the
    interface between its inside (index ior) and air, whose transmitted ray is weighted by k_t
    (transmittance) and, inside, by exp(-absorption * distance). A material that is not double_sided
    is invisible from behind (the side its triangles' winding turns away) to camera, reflection and
    refraction rays, as glTF's doubleSided = false culls back faces; shadow rays still meet it."""

    kd: tuple = (0.7, 0.7, 0.7)
    ka: tuple | None = None  # None: the same as kd, with kd's texture
    ks: tuple = (0.0, 0.0, 0.0)
    shininess: float = 32.0
    reflectivity: tuple = (0.0, 0.0, 0.0)  # k_r
    kd_texture: Texture | None = None
    ka_texture: Texture | None = None
    ks_texture: Texture | None = None
    ior: float | None = None  # eta > 0: a dielectric; None: opaque
    transmittance: tuple = (1.0, 1.0, 1.0)  # k_t, only with ior
    absorption: tuple = (0.0, 0.0, 0.0)  # sigma per scene unit (Beer's law), only with ior
    double_sided: bool = True  # False: back faces culled (an opaque material only)
    # L_e: every object of this material is an area light of this radiance (Scene.emissive_lights),
    # emitting to the side its winding faces, as an ``area`` emitter on a Mitsuba shape or a glTF emissive.
    emission: tuple | None = None
    # Whether ka (its value; its texture) was left to follow kd: a material made again with another kd
    # (Renderer.params) keeps following it, as a file that leaves ka out would.
    ka_follows_kd: bool = field(default=False, init=False, compare=False, repr=False)
    ka_texture_follows_kd: bool = field(default=False, init=False, compare=False, repr=False)

    def __post_init__(self):
        # reflectivity, transmittance and absorption may be one number, as in the scene file.
        _convert(self, vectors=("kd", "ka", "ks", "reflectivity", "transmittance", "absorption", "emission"),
                 scalar_ok=("reflectivity", "transmittance", "absorption"))
        if self.ka is None:
            object.__setattr__(self, "ka", self.kd)
            object.__setattr__(self, "ka_follows_kd", True)
            if self.ka_texture is None:
                object.__setattr__(self, "ka_texture", self.kd_texture)
                object.__setattr__(self, "ka_texture_follows_kd", True)

    @property
    def textures(self) -> dict:
        """The textured colours: {"ka" | "kd" | "ks": Texture}."""
        return {k: t for k, t in (("ka", self.ka_texture), ("kd", self.kd_texture), ("ks", self.ks_texture)) if t}

    def peak(self, key: str) -> np.ndarray:
        """The largest value colour ``key`` (ka, kd, ks) takes anywhere, per channel, before vertex colours."""
        t = getattr(self, f"{key}_texture")
        return np.asarray(getattr(self, key), np.float64) * (t.peak if t is not None else 1.0)

    @property
    def dielectric(self) -> bool:
        return self.ior is not None


# The material "default" of every scene file, which its objects that name no material get.
DEFAULT_MATERIAL = Material(kd=(0.7, 0.7, 0.7), ks=(0.3, 0.3, 0.3), shininess=32.0)


@dataclass
class SceneObject:
    """One object: its triangles in world space (float64), the name of its material, and what it
    has per vertex besides its position. from_shape and from_arrays make one as a scene file's table would."""

    name: str
    vertices: np.ndarray  # (N, 3) float64, world space
    faces: np.ndarray  # (M, 3) int64
    material: str = "default"  # as a scene file's object that names none
    smooth: bool = False
    # Vertex normals (N, 3) for smooth shading, when they are not the ones computed from the
    # triangles alone: the file's own, split at creases, or computed over a whole mesh that was
    # then split by material (so the split leaves no crease).
    normals: np.ndarray | None = None
    uv: np.ndarray | None = None  # (N, 2) texture coordinates, v = 0 at an image's bottom row
    colors: np.ndarray | None = None  # (N, 3) linear RGB, multiplying ka and kd

    def __post_init__(self):
        # Lists (as a notebook writes them) become the arrays the renderer takes; validate.py checks shapes.
        for name, dtype in (("vertices", np.float64), ("faces", None), ("normals", np.float64), ("uv", np.float64),
                            ("colors", np.float64)):
            v = getattr(self, name)
            if v is None or isinstance(v, np.ndarray):
                continue
            try:
                a = np.asarray(v, dtype)
                if a.dtype == object or a.dtype.kind not in "iuf":
                    raise ValueError
            except (TypeError, ValueError):
                raise SceneError("SceneObject", name, f"expected a list of [x, y, z] rows, got {show(v)}") from None
            setattr(self, name, a.astype(np.int64) if name == "faces" and a.dtype.kind in "iu" else a)

    @classmethod
    def from_arrays(cls, name: str, vertices, faces, material: str = "default", *, normals=None, uv=None, colors=None,
                    smooth=None, scale=1.0, rotate=(0.0, 0.0, 0.0), translate=(0.0, 0.0, 0.0), up: str = "y") -> "SceneObject":
        """Triangles from arrays (``vertices`` (N, 3), ``faces`` (M, 3) indices; per vertex optionally
        ``normals``, ``uv``, ``colors``), placed and shaded as a scene file's ``shape = "triangles"`` object
        with the same keys is, or with ``normals`` as a mesh file with its own normals: the same arrays.
        ``smooth``: as the file's, default false, or "auto" (the normals given) where there are normals.
        A bad argument is a SceneError naming it."""
        source = "SceneObject.from_arrays()"
        if normals is not None:
            normals = TableReader(source, {"normals": normals}, "").rows("normals", 3, "[x, y, z] per vertex")
        table = {"shape": "triangles", "name": name, "material": material, "vertices": vertices, "faces": faces,
                 "smooth": ("auto" if normals is not None else False) if smooth is None else smooth,
                 "scale": scale, "rotate": rotate, "translate": translate, "up": up}
        table.update({k: v for k, v in (("uv", uv), ("colors", colors)) if v is not None})
        return cls._from_table(TableReader(source, plain(table), ""), textured=False, normals=normals)

    @classmethod
    def from_shape(cls, shape: str, name: str | None = None, material: str = "default", *, textured: bool = False,
                   smooth=False, scale=1.0, rotate=(0.0, 0.0, 0.0), translate=(0.0, 0.0, 0.0), up: str = "y",
                   **params) -> "SceneObject":
        """A built-in shape (``shape``: sphere, uv_sphere, box, plane, cylinder, torus_knot, triangles) with its
        parameters (``radius=0.5``, ``size=[1, 2, 1]``, ...), as a scene file's [[objects]] table with the same
        keys gives it: the same arrays. ``textured``: with the texture coordinates a file gives the shape when
        its material has a texture (plane, box, uv_sphere). A bad argument is a SceneError naming it."""
        source = "SceneObject.from_shape()"
        if textured and shape not in shapes.WITH_UV and shape != "triangles":
            raise SceneError(source, "textured", f"the {shape!r} shape has no texture coordinates; shapes with "
                                                 f"them: {', '.join(shapes.WITH_UV)}, triangles with uv")
        table = {"shape": shape, **params, "material": material, "smooth": smooth, "scale": scale, "rotate": rotate,
                 "translate": translate, "up": up, **({} if name is None else {"name": name})}
        return cls._from_table(TableReader(source, plain(table), ""), textured=textured)

    @classmethod
    def _from_table(cls, r: TableReader, textured: bool, normals=None) -> "SceneObject":
        """The object of a shape table, through the scene file reader's own reading of one (placement.shape_fields)."""
        return cls(material=r.string("material"), **shape_fields(r, textured, normals))


@dataclass
class Scene:
    """A scene, each field defaulting to what a scene file that leaves it out gets: Camera(), RenderSettings(),
    no lights, the material "default" alone, no objects. As in a file, an object whose material is "default"
    gets DEFAULT_MATERIAL unless ``materials`` defines its own; any other name it lacks is a SceneError
    when the scene is validated (validate_scene, which render() runs)."""

    camera: Camera = field(default_factory=Camera)
    render: RenderSettings = field(default_factory=RenderSettings)
    lights: list[Light] = field(default_factory=list)
    materials: dict[str, Material] = field(default_factory=lambda: {"default": DEFAULT_MATERIAL})
    objects: list[SceneObject] = field(default_factory=list)
    source: str = "<scene>"
    load_seconds: float | None = None  # time load_scene spent reading and validating
    files: tuple = ()  # the files it was read from: the scene file, then the mesh files it names
    cameras: tuple = ()  # the cameras the mesh files define (camera.FileCamera), for `warprt info`

    def __post_init__(self):
        self.lights, self.objects = (list(v) if isinstance(v, tuple) else v for v in (self.lights, self.objects))
        if isinstance(self.materials, dict) and "default" not in self.materials and \
                any(getattr(o, "material", None) == "default" for o in self.objects or ()):
            self.materials = {"default": DEFAULT_MATERIAL, **self.materials}  # first, as a file has it

    @property
    def triangle_count(self) -> int:
        return int(sum(len(o.faces) for o in self.objects))

    @property
    def area_lights(self) -> list:
        """The area lights, in the order of ``lights``, then the emissive materials' (emissive_lights): an
        emitter's index in the kernels' area table."""
        return [light for light in self.lights if light.area] + self.emissive_lights

    @property
    def emissive_lights(self) -> list:
        """An area light per object name whose material has an emission (Material.emission), over that
        object's triangles, in the order of the objects: what a material's emission is, made explicit."""
        lights, named = [], set()
        for o in self.objects:
            m = self.materials.get(o.material) if isinstance(self.materials, dict) else None
            if m is not None and m.emission is not None and max(m.emission) > 0.0 and o.name not in named:
                named.add(o.name)
                lights.append(Light(type="area", radiance=m.emission, object=o.name, name=f"{o.name} ({o.material})"))
        return lights

    @property
    def whitted_lights(self) -> list:
        """The point, spot and directional lights, in the order of ``lights`` (the kernels' light table)."""
        return [light for light in self.lights if not (light.area or light.environment)]

    @property
    def environment(self):
        """The environment light (validate.py allows one), or None."""
        return next((light for light in self.lights if light.environment), None)

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        v = np.concatenate([o.vertices for o in self.objects]) if self.objects else np.zeros((1, 3))
        return v.min(0), v.max(0)

    def with_camera(self, **kw) -> "Scene":
        return replace(self, camera=replace(self.camera, **kw))

    def with_render(self, **kw) -> "Scene":
        return replace(self, render=replace(self.render, **kw))

