"""The two renderers side by side on one scene: images, visible faces per sample, and, where the
faces differ, whether the sample is a tie that both answers describe correctly.

A tie is decided independently of both renderers: the sample's ray (the seed's camera formula in
float64) is intersected with the two triangles in float64. It is a tie when both triangles are hit
at the same depth (a shared edge or crease, or coplanar overlap), or when the nearer one is hit only
within TOL of its boundary (a silhouette edge through the sample): a perturbation far below a
thousandth of a pixel would make the other answer the right one.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from skimage.metrics import structural_similarity

import warprt
from oracle import ray_directions, ray_triangle
from tests.zbuffer.traced import traced_faces
from warprt.geometry import Geometry
from warprt.image import render_zbuffer

TOL = 1e-5  # barycentric (fraction of the triangle) and relative depth; float32 geometry rounds at ~1e-7


@dataclass
class Comparison:
    samples: int
    disagree: int  # samples whose visible face differs
    ties: int  # ... of which the sample is a tie (see the module docstring)
    ssim_raw: float  # the two images as rendered
    ssim: float  # with each tie pixel (every differing sample in it a tie) taken from the tracer in both
    max_diff_agreeing: float  # largest colour difference over pixels whose samples all see the same face
    zbuffer_image: np.ndarray
    tracer_image: np.ndarray
    zbuffer_faces: np.ndarray
    tracer_faces: np.ndarray

    @property
    def agreement_raw(self) -> float:
        return 1.0 - self.disagree / self.samples

    @property
    def agreement(self) -> float:
        """Samples that see the same face, or a tie."""
        return 1.0 - (self.disagree - self.ties) / self.samples


def ssim(a: np.ndarray, b: np.ndarray) -> float:
    """SSIM of two linear images clamped to [0, 1], as displayed."""
    return float(structural_similarity(np.clip(a, 0, 1), np.clip(b, 0, 1), data_range=1.0, channel_axis=-1))


def sample_rays(scene, rows, cols, samples_idx, k: int, samples: int) -> np.ndarray:
    """Float64 directions of the given samples, through the centres of a k x k pixel's strata."""
    if samples > 1:
        sx, sy = (samples_idx % k + 0.5) / k, (samples_idx // k + 0.5) / k
    else:
        sx = sy = np.full(len(rows), 0.5)
    return ray_directions(scene.camera, cols, rows, sx, sy)


def intersect(d: np.ndarray, tri: np.ndarray):
    """Rays from the origin along d (n, 3) against triangles (n, 3, 3): distance along d and the
    smallest barycentric coordinate (negative outside, -inf where the ray is in the plane), in float64."""
    h = ray_triangle(np.zeros(3), d, tri[:, 0], tri[:, 1], tri[:, 2])
    return h.t, np.where(np.isfinite(h.margin), h.margin, -np.inf)


def classify_ties(scene, geometry: Geometry, zb_faces, rt_faces, k: int) -> np.ndarray:
    """For every sample where the faces differ (in np.nonzero order): True if it is a tie."""
    rows, cols, sidx = np.nonzero(zb_faces != rt_faces)
    a, b = zb_faces[rows, cols, sidx], rt_faces[rows, cols, sidx]
    d = sample_rays(scene, rows, cols, sidx, k, zb_faces.shape[2])
    # The rays start at the eye: the triangles as the BVH holds them, made relative to the eye's offset.
    eye = geometry.eye_offset(scene.camera.eye).astype(np.float64)
    tris = geometry.points_np.astype(np.float64)[geometry.indices_np.reshape(-1, 3)] - eye
    far = np.full(len(a), np.inf)
    t_a, m_a = far.copy(), np.full(len(a), -np.inf)
    t_b, m_b = far.copy(), np.full(len(a), -np.inf)
    for f, t, m in ((a, t_a, m_a), (b, t_b, m_b)):
        hit = f >= 0
        t[hit], m[hit] = intersect(d[hit], tris[f[hit]])
        m[~hit] = np.inf  # the background is "hit" everywhere, at infinity
    valid = (m_a >= -TOL) & (m_b >= -TOL) & (t_a > 0) & (t_b > 0)
    same_depth = np.abs(t_a - t_b) <= TOL * np.minimum(t_a, t_b)
    nearer_on_boundary = np.where(t_a < t_b, m_a, m_b) <= TOL
    return valid & (same_depth | nearer_on_boundary)


def compare(scene) -> Comparison:
    geometry = Geometry(scene)
    zb, zb_faces = render_zbuffer(scene, return_faces=True)
    rt = warprt.render(scene, disable=["shadows", "reflection", "refraction", "absorption"], geometry=geometry)
    rt_faces = traced_faces(scene, geometry=geometry)
    assert zb.stats.algorithm == "zbuffer" and rt.stats.algorithm == "raytrace"
    assert zb_faces.shape == rt_faces.shape
    k = math.isqrt(scene.render.spp)
    differ = zb_faces != rt_faces
    tie = np.zeros_like(differ)
    tie[differ] = classify_ties(scene, geometry, zb_faces, rt_faces, k)
    untied = (differ & ~tie).any(-1)
    tie_pixel = differ.any(-1) & ~untied
    zb_image = zb.image.copy()
    zb_image[tie_pixel] = rt.image[tie_pixel]
    agreeing = ~differ.any(-1)
    max_diff = float(np.abs(zb.image - rt.image)[agreeing].max(initial=0.0))
    return Comparison(differ.size, int(differ.sum()), int(tie.sum()), ssim(zb.image, rt.image), ssim(zb_image, rt.image),
                      max_diff, zb.image, rt.image, zb_faces, rt_faces)
