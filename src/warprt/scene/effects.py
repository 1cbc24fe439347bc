"""Which effects a render simulates: derived from the scene, narrowed by the user, never widened.

Each distinct EffectSet compiles to its own kernel variant with the disabled code removed.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from ..errors import ArgumentError, SceneError

EFFECTS = ("ambient", "diffuse", "specular", "shadows", "reflection", "supersampling", "smooth", "texture",
           "vertex_color", "refraction", "absorption")


@dataclass(frozen=True)
class EffectSet:
    ambient: bool = True
    diffuse: bool = True
    specular: bool = True
    shadows: bool = True
    reflection: bool = True
    supersampling: bool = False
    smooth: bool = False
    texture: bool = False
    vertex_color: bool = False
    refraction: bool = False
    absorption: bool = False
    # Not an effect one switches off: whether some light is not the seed's point light without falloff
    # (a spot, a directional light, inverse_square), which needs the general light model in the kernels.
    light_model: bool = False
    # Likewise: whether some material is single-sided, so that camera, reflection and refraction rays
    # pass through its back faces (a scene file's materials are double-sided unless they say otherwise).
    culling: bool = False
    # Likewise: whether some light is an area light, integrated over its sample points (shading.py) and
    # whose emitting triangles show its radiance.
    area_lights: bool = False
    # render.area_estimator = "analytic": a rectangle light's unshadowed diffuse term in closed form, its
    # visibility the ratio estimate over its points (kernels/shading.py make_area_light).
    area_analytic: bool = False
    # render.light_spread with spp > 1: each pixel sample takes its own share of every area light's points and
    # of the environment's directions.
    light_spread: bool = False
    # Likewise: whether the scene has an environment light, seen by the rays that meet nothing and lighting
    # every point from its fixed directions (kernels/environment.py).
    environment: bool = False

    @property
    def names(self) -> tuple[str, ...]:
        """The effects on, by their names in EFFECTS (what render.effects and render(disable=) take)."""
        return tuple(n for n in EFFECTS if getattr(self, n))

    @property
    def variant(self) -> str:
        """A short stable name for the compiled kernel variant: a letter per effect, e.g. 'adsSr' (ambient,
        diffuse, specular, shadows, reflection); the trace kernel's name adds its path, 'trace_adsSr_gshadow'."""
        letters = {"ambient": "a", "diffuse": "d", "specular": "s", "shadows": "S",
                   "reflection": "r", "supersampling": "x", "smooth": "n", "texture": "t", "vertex_color": "c",
                   "refraction": "T", "absorption": "b", "light_model": "L", "culling": "C", "area_lights": "A",
                   "area_analytic": "P", "light_spread": "X", "environment": "E"}
        flags = tuple(n for n in ("light_model", "culling", "area_lights", "area_analytic", "light_spread",
                                  "environment") if getattr(self, n))
        return "".join(letters[n] for n in self.names + flags) or "none"

    def __str__(self) -> str:
        return ",".join(self.names) or "none"


def scene_effects(scene) -> EffectSet:
    """The effects the scene calls for: a term is simulated only where it can change a pixel."""
    used = {o.material for o in scene.objects}
    mats = [scene.materials[m] for m in used]
    amb = np.asarray(scene.render.ambient)
    env = scene.environment
    lit = any(max(l.radiance if l.area else l.color) > 0 for l in scene.whitted_lights + scene.area_lights) or \
        (env is not None and env.scale > 0 and (env.image.peak if env.image is not None else max(env.radiance)) > 0)
    kd = any(max(m.peak("kd")) > 0 for m in mats)
    ks = any(max(m.peak("ks")) > 0 for m in mats)
    return EffectSet(
        ambient=any(np.any(amb * m.peak("ka") > 0) for m in mats),
        diffuse=lit and kd,
        specular=lit and ks,
        shadows=lit and scene.render.shadows and (kd or ks),
        reflection=scene.render.max_depth > 1 and any(max(m.reflectivity) > 0 for m in mats),
        supersampling=scene.render.spp > 1,
        smooth=any(o.smooth for o in scene.objects),
        texture=any(m.textures for m in mats),
        vertex_color=any(getattr(o, "colors", None) is not None for o in scene.objects),
        # A dielectric's ray tree needs a second ray level; Beer's law can act on the first (an eye
        # inside absorbing glass).
        refraction=scene.render.max_depth > 1 and any(m.dielectric for m in mats),
        absorption=any(m.dielectric and max(m.absorption) > 0 for m in mats),
        light_model=not all(light.seed_point for light in scene.whitted_lights),
        culling=not all(m.double_sided for m in mats),
        area_lights=bool(scene.area_lights),
        area_analytic=bool(scene.area_lights) and scene.render.area_estimator == "analytic",
        light_spread=bool(scene.area_lights or env is not None) and scene.render.light_spread and scene.render.spp > 1,
        environment=env is not None,
    )


def parse_effects(names, source: str = "render", field: str = "render.effects") -> set[str]:
    """Effect names as a set; an unknown one is a SceneError naming ``field`` of ``source``, or, with
    source=None, render()'s argument ``field``."""
    out = set()
    for n in names:
        n = n.strip()
        if n == "":
            continue
        if n not in EFFECTS:
            message = f"unknown effect '{n}'; expected some of: {', '.join(EFFECTS)}"
            raise ArgumentError("render", field, message) if source is None else SceneError(source, field, message)
        out.add(n)
    return out


def switched_on(scene, allow=None, disable=()) -> set[str]:
    """The effects neither the scene's render.effects nor ``allow`` (if given) and ``disable`` switch off,
    whether or not the scene's values call for them."""
    keep = set(EFFECTS)
    if scene.render.effects is not None:
        keep &= parse_effects(scene.render.effects, scene.source)
    if allow is not None:
        keep &= parse_effects(allow, None, "effects")
    return keep - parse_effects(disable, None, "disable")


def resolve_effects(scene, allow=None, disable=()) -> EffectSet:
    """The scene's effects, restricted to ``allow`` (if given) and minus ``disable``."""
    fx = scene_effects(scene)
    keep = switched_on(scene, allow, disable)
    on = {n: getattr(fx, n) and n in keep for n in EFFECTS}
    on["shadows"] = on["shadows"] and (on["diffuse"] or on["specular"])  # shadows only dim those terms
    return EffectSet(**on, light_model=fx.light_model, culling=fx.culling, area_lights=fx.area_lights,
                     area_analytic=fx.area_analytic, light_spread=fx.light_spread and on["supersampling"],
                     environment=fx.environment)


def zbuffer_effects(scene, effects=None, disable=()) -> EffectSet:
    """The scene's effect set without what a Z-buffer cannot simulate: shadows, reflections, refraction."""
    return replace(resolve_effects(scene, effects, disable), shadows=False, reflection=False, refraction=False,
                   absorption=False)
