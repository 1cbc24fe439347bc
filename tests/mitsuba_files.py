"""Mitsuba 3 scene files written by the tests: a scene dict (as mi.cornell_box() returns it) as the XML
Mitsuba's parser reads, and the example scenes the XML tests rebuild (Cornell box, textured plane,
glass sphere, spot-lit floor), each with the numbers the tests check the reading against."""

from __future__ import annotations

from pathlib import Path

import numpy as np

# The XML element of each plugin type the scenes use.
_TAGS = {"scene": "scene", "perspective": "sensor", "thinlens": "sensor", "orthographic": "sensor",
         "hdrfilm": "film", "independent": "sampler", "stratified": "sampler", "gaussian": "rfilter", "box": "rfilter",
         "path": "integrator", "direct": "integrator", "aov": "integrator",
         "area": "emitter", "envmap": "emitter", "point": "emitter", "spot": "emitter", "directional": "emitter", "constant": "emitter",
         "diffuse": "bsdf", "plastic": "bsdf", "roughplastic": "bsdf", "conductor": "bsdf", "roughconductor": "bsdf",
         "dielectric": "bsdf", "thindielectric": "bsdf", "twosided": "bsdf", "principled": "bsdf", "mask": "bsdf",
         "normalmap": "bsdf", "bumpmap": "bsdf",
         "rectangle": "shape", "cube": "shape", "sphere": "shape", "disk": "shape", "cylinder": "shape",
         "ply": "shape", "obj": "shape", "bitmap": "texture", "checkerboard": "texture"}


def _numbers(v) -> str:
    return ", ".join(repr(float(x)) for x in np.ravel(np.asarray(v, np.float64)))


def _element(name: str | None, value, top: bool, indent: str) -> list[str]:
    attr = "" if name is None else (f' id="{name}"' if top else f' name="{name}"')
    if isinstance(value, dict):
        kind = value["type"]
        if kind == "ref":
            return [f'{indent}<ref id="{value["id"]}"' + ("" if name is None else f' name="{name}"') + "/>"]
        if kind == "rgb":
            return [f'{indent}<rgb{attr} value="{_numbers(value["value"])}"/>']
        lines = [f'{indent}<{_TAGS[kind]} type="{kind}"{attr}>']
        for key, v in value.items():
            if key != "type":
                lines += _element(key, v, False, indent + "    ")
        return lines + [f"{indent}</{_TAGS[kind]}>"]
    if hasattr(value, "matrix"):  # a mi.ScalarTransform4f
        return [f'{indent}<transform{attr}><matrix value="{_numbers(np.array(value.matrix))}"/></transform>']
    if isinstance(value, bool):
        return [f'{indent}<boolean{attr} value="{str(value).lower()}"/>']
    if isinstance(value, int):
        return [f'{indent}<integer{attr} value="{value}"/>']
    if isinstance(value, float):
        return [f'{indent}<float{attr} value="{value!r}"/>']
    if isinstance(value, str):
        return [f'{indent}<string{attr} value="{value}"/>']
    return [f'{indent}<point{attr} value="{_numbers(value)}"/>']  # a 3-vector


def to_xml(scene: dict) -> str:
    """A Mitsuba scene dict as XML: top-level plugins by id (their key), nested ones by name, references
    as <ref>, transforms as their 4x4 matrix, RGB values as <rgb>."""
    lines = ['<scene version="3.0.0">']
    for key, value in scene.items():
        if key != "type":
            lines += _element(key, value, True, "    ")
    return "\n".join(lines + ["</scene>", ""])


def write(folder, name: str, scene: dict) -> Path:
    path = Path(folder) / name
    path.write_text(to_xml(scene))
    return path


def sensor(mi, origin, target, up=(0.0, 1.0, 0.0), fov=40.0, fov_axis="x", width=64, height=48):
    """A perspective sensor as the test scenes write it: look_at, box filter, one sample at the pixel centre."""
    return {"type": "perspective", "fov": float(fov), "fov_axis": fov_axis,
            "to_world": mi.ScalarTransform4f().look_at(origin=list(origin), target=list(target), up=list(up)),
            "film": {"type": "hdrfilm", "width": width, "height": height, "rfilter": {"type": "box"}},
            "sampler": {"type": "stratified", "sample_count": 1, "jitter": False}}


def floor(mi, size=2.0, bsdf=None):
    """A rectangle of side 2 size in y = 0 facing +y (Mitsuba's rectangle is [-1, 1]^2 in z = 0 facing +z)."""
    to_world = mi.ScalarTransform4f().rotate([1.0, 0.0, 0.0], -90.0).scale([size, size, 1.0])
    return {"type": "rectangle", "to_world": to_world, "bsdf": bsdf or {"type": "diffuse"}}


def cornell_box(mi, width=64, height=48, point_light=(0.0, 0.9, 0.0), intensity=(1.0, 1.0, 1.0), fov_axis=None,
                area_light=True):
    """mi.cornell_box() as it writes it (its area light included unless area_light is False: the
    reference renders Whitted lights only), at a test's image size, with a point light added where the
    test wants one; fov_axis replaces the box's "smaller" when given."""
    d = mi.cornell_box()
    d["sensor"]["film"]["width"], d["sensor"]["film"]["height"] = width, height
    if not area_light:
        del d["light"]["emitter"]
    if fov_axis is not None:
        d["sensor"]["fov_axis"] = fov_axis
    if point_light is not None:
        d["point_light"] = {"type": "point", "position": list(point_light),
                            "intensity": {"type": "rgb", "value": list(intensity)}}
    return d


def checker_png(path, rows=6, cols=8, seed=7) -> Path:
    """A small 8-bit sRGB PNG of random colours (bilinear filtering of it has something to show)."""
    from PIL import Image

    rgb = np.random.default_rng(seed).integers(0, 256, (rows, cols, 3), dtype=np.uint8)
    Image.fromarray(rgb).save(path)
    return Path(path)


def textured_plane(mi, png, width=64, height=48):
    """A floor with a bitmap (scaled 2x by its to_uv) beside one with a checkerboard, under a point light."""
    bitmap = {"type": "bitmap", "filename": str(png), "to_uv": mi.ScalarTransform4f().scale([2.0, 2.0, 1.0])}
    checks = {"type": "checkerboard", "to_uv": mi.ScalarTransform4f().scale([3.0, 3.0, 1.0]),
              "color0": {"type": "rgb", "value": [0.9, 0.8, 0.1]}, "color1": {"type": "rgb", "value": [0.1, 0.2, 0.7]}}
    left = floor(mi, 1.0, {"type": "diffuse", "reflectance": bitmap})
    left["to_world"] = mi.ScalarTransform4f().translate([-1.05, 0.0, 0.0]) @ left["to_world"]
    right = floor(mi, 1.0, {"type": "twosided", "b": {"type": "diffuse", "reflectance": checks}})
    right["to_world"] = mi.ScalarTransform4f().translate([1.05, 0.0, 0.0]) @ right["to_world"]
    # Looking off the origin: a check boundary through the centre row would be a texture lookup tie.
    return {"type": "scene", "sensor": sensor(mi, (0.0, 2.2, 2.6), (0.05, 0.0, 0.13), width=width, height=height),
            "bitmap_floor": left, "checker_floor": right,
            "light": {"type": "point", "position": [0.3, 1.6, 0.8], "intensity": {"type": "rgb", "value": [6.0, 6.0, 6.0]}}}


GLASS = {"center": (0.0, 0.5, 0.0), "radius": 0.5, "int_ior": 1.5, "ext_ior": 1.0}


def glass_sphere(mi, width=64, height=48):
    """A dielectric sphere (GLASS) on a checkerboard floor under a point light."""
    checks = {"type": "checkerboard", "to_uv": mi.ScalarTransform4f().scale([4.0, 4.0, 1.0])}
    return {"type": "scene", "sensor": sensor(mi, (0.0, 1.4, 2.8), (0.0, 0.4, 0.0), width=width, height=height),
            "floor": floor(mi, 2.0, {"type": "diffuse", "reflectance": checks}),
            "glass": {"type": "sphere", "center": list(GLASS["center"]), "radius": GLASS["radius"],
                      "bsdf": {"type": "dielectric", "int_ior": GLASS["int_ior"], "ext_ior": GLASS["ext_ior"]}},
            "light": {"type": "point", "position": [1.0, 2.5, 1.0], "intensity": {"type": "rgb", "value": [8.0, 8.0, 8.0]}}}


SPOT = {"origin": (0.5, 2.0, 0.2), "target": (-0.3, 0.0, 0.1), "cutoff_angle": 30.0, "beam_width": 18.0,
        "intensity": (5.0, 4.0, 3.0), "sun": (1.0, -2.0, 0.5), "irradiance": (0.6, 0.7, 0.8), "sky": (0.1, 0.2, 0.3)}


def spot_lit_floor(mi, width=64, height=48):
    """A floor under a spot (SPOT's look_at and cone), a directional light and a constant sky."""
    s = SPOT
    return {"type": "scene", "sensor": sensor(mi, (0.0, 2.0, 3.0), (0.0, 0.0, 0.0), width=width, height=height),
            "floor": floor(mi, 2.0, {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.8, 0.6, 0.4]}}),
            "lamp": {"type": "spot", "cutoff_angle": s["cutoff_angle"], "beam_width": s["beam_width"],
                     "intensity": {"type": "rgb", "value": list(s["intensity"])},
                     "to_world": mi.ScalarTransform4f().look_at(origin=list(s["origin"]), target=list(s["target"]),
                                                               up=[0.0, 1.0, 0.0])},
            "sun": {"type": "directional", "direction": list(s["sun"]),
                    "irradiance": {"type": "rgb", "value": list(s["irradiance"])}},
            "sky": {"type": "constant", "radiance": {"type": "rgb", "value": list(s["sky"])}}}
