"""The seed's Phong model (its Figure 3) in float64, term by term: the expected colour of every
closed-form shading test and of the brute-force tracer."""

from __future__ import annotations

import numpy as np

TERMS = ("ambient", "diffuse", "specular")


def _material(m):
    """(ka, kd, ks, shininess) of a warprt.scene.Material or of a scene-file dict, with the file's
    defaults (ka = kd, ks = 0, shininess 32)."""
    get = m.get if isinstance(m, dict) else lambda k, default=None: getattr(m, k, default)
    kd = np.asarray(get("kd", (0.7, 0.7, 0.7)), np.float64)
    ka = get("ka", None)
    return (kd if ka is None else np.asarray(ka, np.float64), kd, np.asarray(get("ks", (0.0, 0.0, 0.0)), np.float64),
            float(get("shininess", 32.0)))


def light_source(light):
    """(position, colour C_l) of a warprt.scene.Light, a scene-file dict or a (position, colour) pair."""
    if isinstance(light, dict):
        return np.asarray(light["position"], np.float64), np.asarray(light.get("color", (1.0, 1.0, 1.0)), np.float64)
    if hasattr(light, "position"):
        return np.asarray(light.position, np.float64), np.asarray(light.color, np.float64)
    position, colour = light
    return np.asarray(position, np.float64), np.asarray(colour, np.float64)


def light_direction(p, n, light):
    """The unit direction L = (x_l - p)/|x_l - p| from surface points p (..., 3) to a light, and n.L."""
    position, _ = light_source(light)
    L = position - p
    L = L / np.linalg.norm(L, axis=-1, keepdims=True)
    return L, np.sum(n * L, axis=-1)


def phong_terms(p, n, v, lights, material, c_amb, visible=None) -> dict:
    """The three terms of I = C_amb ka + sum_l vis_l C_l (kd max(0, n.L) + ks max(0, r.v)^shininess)
    at points p with unit normals n facing the viewer and unit directions v towards it (..., 3):
    r = 2 (n.L) n - L is L mirrored about n; a light with n.L <= 0 (behind the surface) adds
    nothing, nor does the highlight where r.v <= 0 (whatever the exponent: 0^0 counts as 0, as in
    both renderers). ``visible``: optional (..., n_lights) booleans, False where a light is shadowed.
    Returns {"ambient", "diffuse", "specular"}: arrays (..., 3)."""
    p, n, v = (np.asarray(x, np.float64) for x in (p, n, v))
    shape = np.broadcast_shapes(p.shape, n.shape, v.shape)
    ka, kd, ks, shininess = _material(material)
    out = {"ambient": np.broadcast_to(np.asarray(c_amb, np.float64) * ka, shape).copy(),
           "diffuse": np.zeros(shape), "specular": np.zeros(shape)}
    for i, light in enumerate(lights):
        _, colour = light_source(light)
        L, n_dot_l = light_direction(p, n, light)
        r = 2.0 * n_dot_l[..., None] * n - L
        r_dot_v = np.sum(r * v, axis=-1)
        on = n_dot_l > 0
        if visible is not None:
            on = on & np.asarray(visible)[..., i]
        with np.errstate(invalid="ignore"):
            highlight = np.where(r_dot_v > 0, np.maximum(r_dot_v, 0.0) ** shininess, 0.0)
        out["diffuse"] = out["diffuse"] + np.where(on[..., None], colour * kd * n_dot_l[..., None], 0.0)
        out["specular"] = out["specular"] + np.where(on[..., None], colour * ks * highlight[..., None], 0.0)
    return out


def phong(p, n, v, lights, material, c_amb, visible=None, terms=TERMS) -> np.ndarray:
    """I = C_amb ka + sum_l vis_l C_l (kd max(0, n.L) + ks max(0, r.v)^shininess), summed over the
    chosen ``terms`` (see phong_terms for the arguments)."""
    parts = phong_terms(p, n, v, lights, material, c_amb, visible)
    shape = parts["ambient"].shape
    return sum((parts[t] for t in terms), np.zeros(shape))
