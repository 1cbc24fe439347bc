"""Secondary rays never re-hit the triangle they leave: >= 100,000 hit points on random triangles
(sizes 1e-4 to 1e4, up to 1e6 from the eye, slivers, hits near edges and vertices), and on large
floors seen from just above, through the renderer's own surface() and offset_ray_origin().

Each triangle sits alone in its own BVH group and rays are traced from that group's root, so any
hit by a mirror ray, and any blocker on a shadow ray to a light on the hit's side, is the
triangle itself. The same rays are traced with the error bound scaled down, to show where
self-intersection starts and so the margin OFFSET_SCALE leaves."""

import numpy as np
import pytest

from marks import slow
from warprt.geometry import build_mesh
from warprt.kernels import OFFSET_SCALE

from stability.probes import EPS32, record, run_offset_probe, surface_tables

SCALES = [0.0, 0.25, 0.5, 1.0, OFFSET_SCALE]  # multiples of the analytic error bound


def unit(rng, n):
    u = rng.normal(size=(n, 3))
    return u / np.linalg.norm(u, axis=1, keepdims=True)


def hemisphere(rng, n, normal, cos_lo):
    """Unit directions on the side of ``normal``, cos(angle) log-uniform in [cos_lo, 1]: many grazing."""
    t = unit(rng, len(normal))
    t -= np.einsum("ni,ni->n", t, normal)[:, None] * normal
    t /= np.linalg.norm(t, axis=1, keepdims=True)
    c = 10 ** rng.uniform(np.log10(cos_lo), 0, len(normal))
    return c[:, None] * normal + np.sqrt(1 - c**2)[:, None] * t


def random_triangles(rng, n):
    """The issue's population: centres up to 1e6 from the eye (log-uniform from 1e-3), sizes 1e-4
    to 1e4 (log-uniform), random shapes; hit points uniform, or within 1e-7..1e-2 of an edge or a vertex."""
    centre = unit(rng, n) * 10 ** rng.uniform(-3, 6, n)[:, None]
    size = 10 ** rng.uniform(-4, 4, n)
    v = (centre[:, None, :] + size[:, None, None] * rng.normal(size=(n, 3, 3))).astype(np.float32)
    b = rng.dirichlet([1, 1, 1], n)
    kind = rng.uniform(size=n)
    tiny = 10 ** rng.uniform(-7, -2, (n, 2))
    edge, vertex = kind < 0.15, (kind >= 0.15) & (kind < 0.3)
    b[edge, 0] = tiny[edge, 0]
    b[edge, 1:] *= ((1 - tiny[edge, 0]) / b[edge, 1:].sum(1))[:, None]
    b[vertex, :2] = tiny[vertex]
    b[vertex, 2] = 1 - tiny[vertex].sum(1)
    return v, rng.permuted(b, axis=1), size


def floor_triangles(rng, n):
    """Large triangles (1 to 1e4 across) in planes passing 1e-4 to 1 times their size below the eye,
    nearly axis-aligned: a floor seen from just above, where the hit point's own error is small
    next to the triangle's extent."""
    size = 10 ** rng.uniform(0, 4, n)
    height = size * 10 ** rng.uniform(-4, 0, n)
    tilt = 10 ** rng.uniform(-4, -1, (n, 2)) * rng.choice([-1, 1], (n, 2))
    angle = rng.uniform(0, 2 * np.pi, n)
    corners = []
    for k in range(3):
        a = angle + k * 2 * np.pi / 3 + rng.uniform(-0.3, 0.3, n)
        x, z = size * np.cos(a), size * np.sin(a)
        corners.append(np.stack([x, -height + tilt[:, 0] * x + tilt[:, 1] * z, z], 1))
    return np.stack(corners, 1).astype(np.float32), rng.dirichlet([1, 1, 1], n), size


def probe_set(kind: str, n: int, seed: int):
    rng = np.random.default_rng(seed)
    v, b, size = (random_triangles if kind == "random" else floor_triangles)(rng, n)
    v64 = v.astype(np.float64)
    normal = np.cross(v64[:, 1] - v64[:, 0], v64[:, 2] - v64[:, 0])
    length = np.linalg.norm(normal, axis=1)
    usable = length > 0  # triangles that are not degenerate in float32
    normal /= np.where(usable, length, 1.0)[:, None]
    target = np.einsum("nj,nji->ni", b, v64)
    # Incoming rays: from the eye (primary rays), or from a nearby point (secondary rays).
    from_eye = rng.uniform(size=n) < (0.5 if kind == "random" else 1.0)
    side = np.where(rng.uniform(size=n) < 0.5, 1.0, -1.0)
    side = np.where(from_eye, np.sign(np.einsum("ni,ni->n", -v64[:, 0], normal)), side)
    near = target + hemisphere(rng, n, normal * side[:, None], 1e-3) * (size * 10 ** rng.uniform(-2, 2, n))[:, None]
    origin = np.where(from_eye[:, None], 0.0, near).astype(np.float32)
    # A point light on the same side, often grazing (cos down to 1e-4), 1e-3 to 1e3 sizes away.
    light = (target + hemisphere(rng, n, normal * side[:, None], 1e-4) * (size * 10 ** rng.uniform(-3, 3, n))[:, None])
    light = light.astype(np.float32)
    # The float32 scene decides sides: the incoming origin and the light must lie strictly on the
    # same side of the float32 triangle's plane (computed in float64), or the case is not posed.
    height = lambda p: np.einsum("ni,ni->n", p.astype(np.float64) - v64[:, 0], normal)
    h_light = height(light)
    posed = usable & (np.sign(height(origin)) == side) & (np.sign(h_light) == side)
    # A light closer to the plane than 4 float32 roundings of the coordinates involved sits on the
    # surface as far as float32 can tell; those shadow rays are counted apart.
    reach = np.maximum(np.abs(v64).max(axis=(1, 2)), np.abs(light).max(axis=1))
    clear = np.abs(h_light) >= 4 * EPS32 * reach
    mesh, points, indices = build_mesh(v.reshape(-1, 3), np.arange(3 * n, dtype=np.int32), groups=np.arange(n, dtype=np.int32))
    tables = surface_tables(mesh, points, indices, n)
    return (mesh, points, indices, tables), origin, target.astype(np.float32), light, posed, clear


@slow
@pytest.mark.parametrize("kind,n,seed", [("random", 135_000, 1), ("floor", 115_000, 2)])
def test_secondary_rays_never_hit_their_own_triangle(kind, n, seed):
    keep, origin, target, light, posed, clear = probe_set(kind, n, seed)
    tables = keep[3]
    rows = {}
    for scale in SCALES:
        out = run_offset_probe(tables, origin, target, light, scale)
        hit = (out[:, 0] == 1) & posed
        shadow = hit & (out[:, 2] == 1)
        rows[scale] = {"hit_points": int(hit.sum()), "mirror_self_hits": int(out[hit, 1].sum()),
                       "shadow_rays": int((shadow & clear).sum()), "shadow_blocked": int(out[shadow & clear, 3].sum()),
                       "lights_on_surface": int((shadow & ~clear).sum()),
                       "lights_on_surface_blocked": int(out[shadow & ~clear, 3].sum())}
    record(f"self_intersection/{kind}", {f"{s:g}x bound": r for s, r in rows.items()} | {"OFFSET_SCALE": OFFSET_SCALE})
    rendered = rows[OFFSET_SCALE]
    assert rendered["hit_points"] >= 100_000 and rendered["shadow_rays"] >= 90_000
    assert rendered["mirror_self_hits"] == 0
    assert rendered["shadow_blocked"] == 0
    # The probe sees self-intersection when the offset is missing.
    assert rows[0.0]["mirror_self_hits"] > 1000 and rows[0.0]["shadow_blocked"] > 1000
