"""Whitted's adaptive supersampling (T. Whitted, "An Improved Illumination Model for Shaded Display", 1980: a
pixel's corners compared and the pixel subdivided where they differ), as ``render.adaptive`` = t > 0: the frame is
traced at each pixel's centre, and the render.spp samples (k x k strata) are traced only in the pixels whose 3 x 3
neighbourhood of centres holds a colour more than t away from theirs in some channel. A straight edge that crosses
a pixel always parts its centre from one of its eight neighbours' (a neighbour lies at least a pixel along any
normal, the edge within 0.71 of the centre), so every pixel an edge crosses is refined unless the colours either
side are within t; what is finer than a pixel between the centres (a sliver, a thin line) can be missed, as it
can by any sampler that looks before it refines. A refined pixel is the render.spp frame's, to the bit (the trace
kernel's walk at the same strata, kernels.make_pixels_kernel); the others are their centres' colour, which a
smooth shading's box-filtered pixel is to second order. Deterministic: the same image on every run and for any
number of threads. AOVs are the centre frame's (one sample a pixel). What it is for: the samples go where the edges are (benchmarks/REPORT.md, "Soft shadows and sky light at
equal error": the sampled estimator's frames at equal error in half the time)."""

from __future__ import annotations

import math

import numpy as np

from .._warp import wp
from ..kernels import camera_data, empty_aov_buffers, empty_record, make_pixels_kernel
from ..scene import camera_basis
from .launch import launch_bands
from .mirrors import empty_mirrors
from .zbuffer import empty_fragments


def adaptive_spp(scene, fx, grad: bool) -> int:
    """The k of the frame's k x k strata where render.adaptive refines it (0: a plain frame): adaptive on, more
    than one sample a pixel and supersampling not switched off, not a grad=True frame (backward's record is that
    of every pixel's strata; renderer.render refuses the two together)."""
    k = math.isqrt(scene.render.spp)
    return k if scene.render.adaptive > 0 and k > 1 and fx.supersampling and not grad else 0


def refined_pixels(image: np.ndarray, threshold: float) -> np.ndarray:
    """Row-major indices (int32, ascending) of the pixels of ``image`` (height, width, 3) whose 3 x 3
    neighbourhood (the image's border repeated) holds a colour more than ``threshold`` from theirs in some
    channel."""
    h, w, _ = image.shape
    padded = np.pad(image, ((1, 1), (1, 1), (0, 0)), mode="edge")
    step = np.zeros((h, w), image.dtype)
    for dy in range(3):
        for dx in range(3):
            np.maximum(step, np.abs(padded[dy:dy + h, dx:dx + w] - image).max(axis=2), out=step)
    return np.flatnonzero(step > threshold).astype(np.int32)


def refine(scene, plan, geom, data, image: np.ndarray, k: int, device: str, pool=None) -> tuple:
    """(image, per_kind, refined): ``image`` (the pixel-centre frame's, (height, width, 3)) with the pixels
    refined_pixels picks traced at k x k samples with ``plan``'s effects (the spp frame's: its supersampling,
    its lights spread over the samples, ``data`` their table) (kernels.make_pixels_kernel, in bands on the frame's threads),
    the rays they took by kind (camera, shadow, reflection[, refraction]) and how many pixels were refined."""
    cam = scene.camera
    pixels = refined_pixels(image, scene.render.adaptive)
    n = len(pixels)
    per_kind = np.zeros(4 if plan.fx.refraction else 3, np.int64)
    if n == 0:
        return image, per_kind, 0
    kernel = make_pixels_kernel(plan.fx, plan.stack)
    listed = wp.array(pixels, dtype=int, device=device)
    colour = wp.empty(n, dtype=wp.vec3, device=device)
    counts = wp.empty(n, dtype=wp.vec4i if plan.fx.refraction else wp.vec3i, device=device)
    c = camera_data(camera_basis(cam), geom.eye_offset(cam.eye))
    stand_ins = [empty_fragments(device), empty_mirrors(device), empty_aov_buffers(device), empty_record(device)]
    launch_bands(kernel, lambda first: [data, c, plan.max_depth, k, first, listed, *stand_ins, colour, counts], n,
                 plan.threads, plan.bands, device, pool=pool)
    out = image.copy()
    out.reshape(-1, 3)[pixels] = colour.numpy()
    return out, counts.numpy().sum(0, dtype=np.int64), n
