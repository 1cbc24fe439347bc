"""An environment light on the host: its equirectangular radiance as Mitsuba's ``envmap`` holds and reads it,
and its fixed, importance-sampled directions with their weights L(w) / (pdf(w) N).

Mitsuba's conventions (emitters/envmap.cpp), followed exactly so that a file's envmap and its TOML twin render
alike: a local direction d = to_world^-1 w has u = atan2(d.x, -d.z) / 2 pi, v = acos(d.y) / pi (+y the pole,
image row 0 at v = 0); the image gets a copy of its first column at its end (periodic), texel column i sits at
u = (i + 1/2) / W and row j at v = j / (H - 1) (the first and last rows at the poles), read bilinearly.

The directions: the cells between neighbouring texels (W columns, H - 1 rows) are chosen with probability
proportional to their mean luminance times their solid angle, then a direction within the cell with density
proportional to the luminance interpolated bilinearly between its corners (in phi and cos theta, so that
L / pdf is nearly constant across a cell even at a sun's edge; a cell of constant mean luminance sampled
uniformly left 2% of the sun-lit floor of scenes/envmap.xml missing at 1,024 directions). The map from the unit
square is inverted (the row from the first coordinate through the marginal, the column from the second through
the row's conditional) at the N = light_samples points of the Fibonacci lattice ((i + 1/2) / N, (i + 1/2) / phi
mod 1), as area.py samples a mesh, so the same N directions light every point, each at its own height: the
centres of a k x k grid give only k heights, and a disk's shadow overhead came out 25% too bright at 64
directions and 4% too dark at 256 (the lattice: 2.7% and 0.8%), and Mitsuba's converged direct image of
scenes/envmap.xml at SSIM 0.9942 against 0.9969 (256 directions, 9 samples a pixel). A constant environment's
directions are uniform on the sphere, and those above a plane facing +y integrate its cosine by the midpoint
rule, exactly.
"""

from __future__ import annotations

import numpy as np

from .area import fibonacci_lattice
from .placement import rotation

LUMINANCE = np.array([0.212671, 0.715160, 0.072169])  # Mitsuba's luminance() of linear sRGB
CONSTANT_SIZE = (3, 2)  # rows, columns of a constant radiance's image: Mitsuba's smallest envmap


def to_world(light) -> np.ndarray:
    """The 3 x 3 rotation taking the environment's local directions to the world's (Mitsuba's to_world)."""
    return rotation(light.rotate)


def environment_texels(light) -> np.ndarray:
    """(H, W + 1, 3) float64: the radiance image times scale, row 0 at the +y pole (v = 0), its first column
    repeated at its end (Mitsuba's periodic column); a constant radiance as a 3 x 2 image of it."""
    if light.image is not None:
        img = np.asarray(light.image.image, np.float64)[::-1, :, :3]  # textures keep row 0 at v = 0 of uv's v
    else:
        img = np.broadcast_to(np.asarray(light.radiance, np.float64), CONSTANT_SIZE + (3,))
    img = img * float(light.scale)
    return np.ascontiguousarray(np.concatenate([img, img[:, :1]], axis=1))


def direction_to_uv(d: np.ndarray) -> np.ndarray:
    """Mitsuba's direction_to_uv of local directions (N, 3)."""
    u = np.arctan2(d[:, 0], -d[:, 2]) / (2 * np.pi)
    v = np.arccos(np.clip(d[:, 1], -1.0, 1.0)) / np.pi
    return np.stack([u, v], -1)


def uv_to_direction(u: np.ndarray, cos_theta: np.ndarray) -> np.ndarray:
    """Mitsuba's uv_to_direction, the polar angle given by its cosine."""
    phi = 2 * np.pi * u
    sin_theta = np.sqrt(np.maximum(1.0 - cos_theta * cos_theta, 0.0))
    return np.stack([np.sin(phi) * sin_theta, cos_theta, -np.cos(phi) * sin_theta], -1)


def lookup(texels: np.ndarray, uv: np.ndarray) -> np.ndarray:
    """The bilinear radiance at uv (N, 2): Mitsuba's eval_spectrum over the padded texels."""
    h, w = texels.shape[:2]
    u = uv[:, 0] - 0.5 / (w - 1)
    u = (u - np.floor(u)) * (w - 1)
    v = uv[:, 1] * (h - 1)
    x = np.minimum(u.astype(np.int64), w - 2)
    y = np.minimum(v.astype(np.int64), h - 2)
    fx, fy = (u - x)[:, None], (v - y)[:, None]
    top = (1 - fx) * texels[y, x] + fx * texels[y, x + 1]
    bottom = (1 - fx) * texels[y + 1, x] + fx * texels[y + 1, x + 1]
    return (1 - fy) * top + fy * bottom


def _invert(cdf: np.ndarray, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(index, fraction within it) of x in [0, 1) under a piecewise-constant distribution's cdf (n + 1 values)."""
    i = np.clip(np.searchsorted(cdf, x, side="right") - 1, 0, len(cdf) - 2)
    while np.any(cdf[i + 1] <= cdf[i]):  # a cell of probability 0 is never chosen: the next one that has some
        step = cdf[i + 1] <= cdf[i]
        i = np.where(step, i + 1, i)
    return i, np.clip((x - cdf[i]) / (cdf[i + 1] - cdf[i]), 0.0, 1.0)


def _linear(a: np.ndarray, b: np.ndarray, x: np.ndarray) -> np.ndarray:
    """The inverse cdf at x of the density on [0, 1] proportional to a (1 - t) + b t (a, b >= 0, not both 0)."""
    root = np.sqrt(np.maximum(a * a + x * (b * b - a * a), 0.0))
    return np.where(a + root > 0.0, x * (a + b) / np.maximum(a + root, 1e-300), x)


def environment_samples(light, n: int) -> tuple[np.ndarray, np.ndarray]:
    """(directions (n, 3) world unit vectors towards the environment, weights (n, 3) = L(w) / (pdf(w) n)) (the
    module docstring); an environment that is black everywhere has no directions."""
    texels = environment_texels(light)
    h, w = texels.shape[0], texels.shape[1] - 1
    lum = np.maximum(texels @ LUMINANCE, 0.0)
    corners = np.stack([lum[:-1, :-1], lum[:-1, 1:], lum[1:, :-1], lum[1:, 1:]])  # b00, b10, b01, b11 per cell
    cos_edges = np.cos(np.arange(h) * np.pi / (h - 1))
    solid = (cos_edges[:-1] - cos_edges[1:])[:, None] * (2 * np.pi / w)  # each cell's solid angle
    weight = corners.mean(0) * solid
    total = weight.sum()
    if not total > 0.0:
        return np.zeros((0, 3)), np.zeros((0, 3))
    rows = weight.sum(1)
    b, a = fibonacci_lattice(n)  # a = (i + 1/2) / N picks the row: each direction its own
    row, t_row = _invert(np.concatenate([[0.0], np.cumsum(rows)]) / total, a)
    col = np.empty(len(a), np.int64)
    t_col = np.empty(len(a))
    for j in np.unique(row):
        at = row == j
        col[at], t_col[at] = _invert(np.concatenate([[0.0], np.cumsum(weight[j])]) / rows[j], b[at])
    # Within the cell, the luminance's bilinear density: t (down the cell, linear in cos theta) from its
    # marginal, then s (along phi) given t.
    b00, b10, b01, b11 = corners[:, row, col]
    t = _linear(b00 + b10, b01 + b11, t_row)
    left, right = b00 + t * (b01 - b00), b10 + t * (b11 - b10)
    s = _linear(left, right, t_col)
    density = left + s * (right - left)  # the luminance's bilinear value there: pdf(w) = density / total
    cos_theta = cos_edges[row] + t * (cos_edges[row + 1] - cos_edges[row])
    local = uv_to_direction((col + 0.5 + s) / w, cos_theta)
    radiance = lookup(texels, direction_to_uv(local))
    inv_pdf = np.where(density > 0.0, total / np.maximum(density, 1e-300), 0.0)
    return local @ to_world(light).T, radiance * inv_pdf[:, None] / len(a)
