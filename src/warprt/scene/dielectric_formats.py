"""What mesh files say about glass, as Material fields: MTL's Ni, illum and Tf, glTF's
KHR_materials_ior and KHR_materials_transmission, USD's UsdPreviewSurface ior and opacity. Each
function returns the fields to replace on the material the file's other statements make ({} for an
opaque one); a bad value is a SceneError naming the file's own field."""

from __future__ import annotations

import math

import numpy as np

from ..errors import SceneError, show

# MTL illumination models with a refracted ray: 4 (glass, ray-traced reflection), 6 (refraction),
# 7 (refraction and Fresnel reflection).
MTL_DIELECTRIC_ILLUM = (4, 6, 7)
# The index glTF (KHR_materials_ior) and UsdPreviewSurface default to; an MTL glass without Ni gets it too.
DEFAULT_IOR = 1.5


def _numbers(v) -> list[float] | None:
    try:
        return [float(x) for x in np.atleast_1d(v)]
    except (TypeError, ValueError):
        return None


def dielectric_from_mtl(raw: dict, source: str = "<mtl>", name: str = "?") -> dict:
    """MTL statements (trimesh's lower-case keys, values as written): illum 4, 6 or 7 makes a
    dielectric of index Ni (DEFAULT_IOR when absent) and transmittance Tf (one or three numbers in
    [0, 1]); Ni alone, written by most exporters for every material, does not."""
    illum = _numbers(raw.get("illum"))
    if not illum or int(illum[0]) not in MTL_DIELECTRIC_ILLUM:
        return {}
    ior = DEFAULT_IOR
    if "ni" in raw:
        v = _numbers(raw["ni"])
        if not v or not (math.isfinite(v[0]) and v[0] > 0.0):
            raise SceneError(source, f"newmtl {name}: Ni", f"expected a number > 0, got {show(raw['ni'])}")
        ior = v[0]
    out = {"ior": ior, "reflectivity": (0.0, 0.0, 0.0)}
    if "tf" in raw:
        v = _numbers(raw["tf"])
        if v is not None and len(v) == 1:
            v = v * 3
        if v is None or len(v) != 3 or not all(math.isfinite(x) and 0.0 <= x <= 1.0 for x in v):
            raise SceneError(source, f"newmtl {name}: Tf", f"expected 1 or 3 numbers in [0, 1], got {show(raw['tf'])}")
        out["transmittance"] = tuple(v)
    return out


def dielectric_from_gltf(material: dict, source: str = "<gltf>", where: str = "material") -> dict:
    """A glTF material (its JSON) with KHR_materials_transmission's transmissionFactor t > 0: a
    dielectric of index KHR_materials_ior's ior (1.5 by default). glTF mixes the diffuse lobe and the
    transmitted light, both tinted by the base colour, in the ratio 1 - t : t, so kd = (1 - t) base
    and k_t = t base."""
    ext = material.get("extensions") or {}
    transmission = ext.get("KHR_materials_transmission")
    if not isinstance(transmission, dict):
        return {}
    t = transmission.get("transmissionFactor", 0.0)
    if isinstance(t, bool) or not isinstance(t, (int, float)) or not 0.0 <= t <= 1.0:
        raise SceneError(source, f"{where}.extensions.KHR_materials_transmission.transmissionFactor",
                         f"expected a number in [0, 1], got {show(t)}")
    if t == 0.0:
        return {}
    ior = (ext.get("KHR_materials_ior") or {}).get("ior", DEFAULT_IOR)
    if isinstance(ior, bool) or not isinstance(ior, (int, float)) or not (math.isfinite(ior) and ior > 0.0):
        raise SceneError(source, f"{where}.extensions.KHR_materials_ior.ior", f"expected a number > 0, got {show(ior)}")
    base = (material.get("pbrMetallicRoughness") or {}).get("baseColorFactor", [1.0, 1.0, 1.0, 1.0])
    base = np.clip(np.asarray(_numbers(base) or [1.0, 1.0, 1.0], np.float64)[:3], 0.0, 1.0)
    kd = tuple(float(x) for x in (1.0 - t) * base)
    return {"ior": float(ior), "transmittance": tuple(float(x) for x in t * base), "kd": kd, "ka": kd}


def dielectric_from_usd(shader) -> dict:
    """A UsdPreviewSurface shader (a UsdShade.Shader) with opacity < 1 and no opacityThreshold (which
    would make opacity a cut-out mask): a dielectric of its ior (1.5 unless authored), transmittance
    1 - opacity, the diffuse colour weighted by opacity."""
    def value(name, default):
        inp = shader.GetInput(name)
        v = inp.Get() if inp else None
        return default if v is None else v

    opacity = float(value("opacity", 1.0))
    if not opacity < 1.0 or float(value("opacityThreshold", 0.0)) > 0.0:
        return {}
    opacity = max(0.0, opacity)
    ior = float(value("ior", DEFAULT_IOR))
    if not (math.isfinite(ior) and ior > 0.0):
        raise SceneError(str(shader.GetPrim().GetStage().GetRootLayer().identifier), f"{shader.GetPath()}.inputs:ior",
                         f"expected a number > 0, got {ior:g}")
    kd = tuple(max(0.0, float(x)) * opacity for x in value("diffuseColor", (0.18, 0.18, 0.18)))
    return {"ior": ior, "transmittance": (1.0 - opacity,) * 3, "kd": kd, "ka": kd}
