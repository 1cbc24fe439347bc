"""The AOVs on the host: their names, what each holds, how the kernel's per-pixel sums become the
arrays render() returns, and the channels each is written as in an OpenEXR file (film.py)."""

from __future__ import annotations

import numpy as np

from ..options import AOVS, check_aovs  # noqa: F401 (the names and their check live with the options)

# Definitions (first hits of camera rays; misses: depth +inf, ids -1, the rest 0):
#   depth      distance from the eye to the hit along the ray                    float32 (H, W)
#   normal     world-space shading normal, turned to face the camera              float32 (H, W, 3)
#   albedo     the diffuse colour at the hit as the shading reads it: kd times its   float32 (H, W, 3)
#              texture and the vertex colour, where the scene (and its effect set) has them
#   position   world-space hit point, float64: the geometry's float64 origin plus float64 (H, W, 3)
#              the float32 hit relative to it
#   uv         as Mitsuba's: the object's texture coordinates at the hit where it has  float32 (H, W, 2)
#              them, else the hit's barycentrics (b1, b2), p = (1-b1-b2) p0 + b1 p1 + b2 p2
#   object     index in scene.objects                                             int32 (H, W)
#   material   index in scene.materials (in its order, "default" first)           int32 (H, W)
#   face       triangle index within its object                                   int32 (H, W)
#   coverage   share of the pixel's samples that hit                              float32 (H, W)
# Geometric AOVs (depth .. uv) are averaged over the pixel's samples that hit; the ID AOVs (object,
# material, face) are the sample's nearest the pixel centre (kernels.id_sample), never averaged.
IDS = ("object", "material", "face")

# OpenEXR channels of each AOV, "layer.channel" as compositors group them. EXR has no signed
# integers: the IDs are UINT channels holding the int32 bits, so -1 (no hit) reads back as 4294967295.
CHANNELS = {"depth": ("depth.Z",), "normal": ("normal.X", "normal.Y", "normal.Z"),
            "albedo": ("albedo.R", "albedo.G", "albedo.B"), "position": ("position.X", "position.Y", "position.Z"),
            "uv": ("uv.U", "uv.V"), "object": ("object.id",), "material": ("material.id",), "face": ("face.id",),
            "coverage": ("coverage.A",)}


def finish_aovs(names, sums: dict, samples: int, origin, height: int, width: int) -> dict:
    """The AOV arrays from the kernel's per-pixel sums (kernels.aov_sums): geometric AOVs divided by
    the pixel's hit count, position moved to world space in float64, coverage = hits / samples."""
    hits = sums["hits"].reshape(height, width)
    hit = hits > 0
    n = np.maximum(hits, 1).astype(np.float64)
    out = {}
    for name in names:
        if name == "coverage":
            out[name] = (hits / float(samples)).astype(np.float32)
        elif name in IDS:
            out[name] = sums[name].reshape(height, width).astype(np.int32)
        elif name == "depth":
            out[name] = np.where(hit, sums[name].reshape(height, width) / n, np.inf).astype(np.float32)
        else:
            mean = sums[name].reshape(height, width, -1).astype(np.float64) / n[..., None]
            if name == "position":
                out[name] = np.where(hit[..., None], np.asarray(origin, np.float64) + mean, 0.0)
            else:
                out[name] = mean.astype(np.float32)
    return out
