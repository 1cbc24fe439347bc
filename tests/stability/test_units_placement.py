"""Units and placement do not change the picture: the same scene scaled by 1e-3 and 1e3 (camera
and lights too) and translated by 1e4 and 1e5 renders with SSIM >= 0.999 against the original.

(For reference, the issue measured Mitsuba 3 at SSIM 0.85 for a 3.6e4 translation and 0.935 for
a 1e-3 scale: its fixed relative ray offset breaks shadows and reflections there.)"""

import copy

import numpy as np
import pytest
from skimage.metrics import structural_similarity

import warprt
from warprt.scene import scene_from_dict

from stability.probes import record

# Shadows (a sphere and a box on a floor, two lights), a reflective floor and a mirror that shows
# the other objects and whose own shadow-casting edge is in view: every offset is exercised.
SCENE = {
    "camera": {"eye": [0.3, 1.7, 6.2], "center": [0.0, 0.8, 0.0], "up": [0.0, 1.0, 0.0], "fovy": 45.0,
               "near": 1.0, "width": 128, "height": 96},
    "render": {"ambient": [0.08] * 3, "background": [0.02, 0.03, 0.06], "max_depth": 4},
    "lights": [{"position": [4.0, 6.0, 5.0], "color": [0.8] * 3}, {"position": [-5.0, 4.0, 3.0], "color": [0.35, 0.35, 0.45]}],
    "materials": {
        "floor": {"kd": [0.22, 0.24, 0.22], "ks": [0.1] * 3, "shininess": 16.0, "reflectivity": 0.25},
        "red": {"kd": [0.75, 0.12, 0.1], "ks": [0.6] * 3, "shininess": 64.0},
        "blue": {"kd": [0.15, 0.25, 0.7], "ks": [0.3] * 3, "shininess": 24.0, "reflectivity": 0.2},
        "mirror": {"kd": [0.03] * 3, "ks": [0.4] * 3, "shininess": 128.0, "reflectivity": 0.85},
    },
    "objects": [
        {"shape": "plane", "size": [14.0, 14.0], "material": "floor"},
        {"shape": "sphere", "radius": 0.9, "subdivisions": 4, "smooth": True, "material": "red", "translate": [-0.9, 0.9, 0.4]},
        {"shape": "box", "size": [1.0, 1.4, 1.0], "rotate": [0.0, 30.0, 0.0], "translate": [1.2, 0.7, 0.9], "material": "blue"},
        {"shape": "box", "size": [6.0, 3.2, 0.1], "translate": [0.0, 1.6, -2.2], "material": "mirror"},
    ],
}


# Glass: a smooth ball refracting the floor and a mirror, an absorbing cube whose colour depends on the
# path length inside (absorption is per scene unit, so it scales by 1 / scale), shadows through both.
GLASS_SCENE = copy.deepcopy(SCENE)
GLASS_SCENE["render"]["max_depth"] = 6
GLASS_SCENE["materials"]["glass"] = {"ior": 1.5, "ka": [0.0] * 3, "kd": [0.0] * 3, "ks": [0.5] * 3, "shininess": 100.0}
GLASS_SCENE["materials"]["tinted"] = {"ior": 1.4, "ka": [0.0] * 3, "kd": [0.0] * 3, "absorption": [1.5, 0.6, 0.1]}
GLASS_SCENE["objects"][1]["material"] = "glass"
GLASS_SCENE["objects"][2].update(material="tinted", translate=[1.2, 0.75, 0.9])  # its bottom face off the floor: no tie


def transformed(scale: float, shift: float, base: dict = SCENE) -> dict:
    """The whole scene mapped by x -> scale x + shift (1, 1, 1): objects, camera and lights."""
    doc = copy.deepcopy(base)
    move = lambda p: [scale * x + shift for x in p]
    for key in ("eye", "center"):
        doc["camera"][key] = move(doc["camera"][key])
    doc["camera"]["near"] *= scale
    for light in doc["lights"]:
        light["position"] = move(light["position"])
    for obj in doc["objects"]:
        s = obj.get("scale", 1.0)
        obj["scale"] = [scale * x for x in s] if isinstance(s, list) else scale * s
        obj["translate"] = move(obj.get("translate", [0.0, 0.0, 0.0]))
    for material in doc["materials"].values():
        if "absorption" in material:
            material["absorption"] = [sigma / scale for sigma in material["absorption"]]
    return doc


def render(doc):
    image, stats = warprt.render(scene_from_dict(doc, "<units>"), threads=2)
    return np.clip(image, 0.0, 1.0).astype(np.float64), stats  # SSIM in float64: 1 - SSIM stays visible


@pytest.fixture(scope="module")
def original():
    image, stats = render(transformed(1.0, 0.0))
    assert stats.rays["shadow"] > 0 and stats.rays["reflection"] > 0
    return image


@pytest.mark.parametrize("scale,shift", [(1e-3, 0.0), (1e3, 0.0), (1.0, 1e4), (1.0, 1e5), (1e-3, 1e5), (1e-9, 0.0), (1e9, 0.0)],
                         ids=["scale 1e-3", "scale 1e3", "translate 1e4", "translate 1e5", "scale 1e-3 translate 1e5",
                              "scale 1e-9", "scale 1e9"])
def test_same_picture_at_any_scale_and_place(original, scale, shift):
    image, _ = render(transformed(scale, shift))
    ssim = structural_similarity(original, image, data_range=1.0, channel_axis=-1)
    diff = np.abs(image - original)
    record(f"units_placement/scale {scale:g} translate {shift:g}",
           {"ssim": float(ssim), "one_minus_ssim": float(1.0 - ssim), "max_abs_diff": float(diff.max()), "pixels_off_1e-3": int((diff.max(-1) > 1e-3).sum())})
    assert ssim >= 0.999


@pytest.fixture(scope="module")
def original_glass():
    image, stats = render(transformed(1.0, 0.0, GLASS_SCENE))
    assert stats.rays["refraction"] > 0 and stats.rays["shadow"] > 0
    return image


@pytest.mark.parametrize("scale,shift", [(1e-3, 0.0), (1e3, 0.0), (1.0, 1e5)], ids=["scale 1e-3", "scale 1e3", "translate 1e5"])
def test_glass_renders_the_same_at_any_scale_and_place(original_glass, scale, shift):
    image, _ = render(transformed(scale, shift, GLASS_SCENE))
    ssim = structural_similarity(original_glass, image, data_range=1.0, channel_axis=-1)
    diff = np.abs(image - original_glass)
    record(f"units_placement/glass scale {scale:g} translate {shift:g}",
           {"ssim": float(ssim), "one_minus_ssim": float(1.0 - ssim), "max_abs_diff": float(diff.max()),
            "pixels_off_1e-3": int((diff.max(-1) > 1e-3).sum())})
    assert ssim >= 0.999
