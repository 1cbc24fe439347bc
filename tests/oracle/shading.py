"""The seed's Phong model (its Figure 3) in float64, term by term, with point, spot and directional
lights and their falloff: the expected colour of every closed-form shading test and of the brute-force tracer."""

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


def _field(light, key, default=None):
    if isinstance(light, dict):
        return light.get(key, default)
    if isinstance(light, tuple):  # a (position, colour) pair: a point light without falloff
        return default
    v = getattr(light, key, default)
    return default if v is None else v


def light_source(light):
    """(position, colour C_l) of a warprt.scene.Light, a scene-file dict or a (position, colour) pair;
    position None for a directional light."""
    if isinstance(light, tuple):
        position, colour = light
    else:
        position, colour = _field(light, "position"), _field(light, "color", (1.0, 1.0, 1.0))
    return (None if position is None else np.asarray(position, np.float64)), np.asarray(colour, np.float64)


def light_kind(light) -> str:
    return _field(light, "type", "point")


def light_axis(light) -> np.ndarray:
    """The unit direction a spot or directional light travels along."""
    d = np.asarray(_field(light, "direction"), np.float64)
    if _field(light, "target") is not None:  # a scene-file spot may give its target instead
        d = np.asarray(_field(light, "target"), np.float64) - light_source(light)[0]
    return d / np.linalg.norm(d)


def light_direction(p, n, light):
    """The unit direction L from surface points p (..., 3) to a light and n.L: (x_l - p)/|x_l - p|, or
    minus the direction of a directional light (a sun: the same L everywhere)."""
    p = np.asarray(p, np.float64)
    if light_kind(light) == "directional":
        L = np.broadcast_to(-light_axis(light), p.shape)
    else:
        L = light_source(light)[0] - p
        L = L / np.linalg.norm(L, axis=-1, keepdims=True)
    return L, np.sum(n * L, axis=-1)


def spot_profile(theta, cutoff_angle: float, beam_width: float | None = None):
    """A spot's profile at angle theta (radians) off its axis, as Mitsuba documents its ``spot``: 1 within
    beam_width, then falling linearly in the angle to 0 at cutoff_angle (degrees; beam_width defaults to
    3/4 of the cutoff), 0 beyond."""
    cutoff = np.radians(cutoff_angle)
    beam = np.radians(0.75 * cutoff_angle if beam_width is None else beam_width)
    theta = np.asarray(theta, np.float64)
    with np.errstate(divide="ignore", invalid="ignore"):
        ramp = (cutoff - theta) / (cutoff - beam)
    return np.where(theta <= beam, 1.0, np.where(theta < cutoff, ramp, 0.0))


def light_intensity(p, light) -> np.ndarray:
    """What light arrives at points p (..., 3) per unit n.L: C_l, times a spot's profile at the angle
    between its axis and p, over r^2 with falloff "inverse_square" (r = |p - x_l|); a directional
    light's C_l is its irradiance on a surface facing it (Lambert's cos law is the n.L)."""
    p = np.asarray(p, np.float64)
    position, colour = light_source(light)
    factor = np.ones(p.shape[:-1])
    if light_kind(light) != "directional":
        x = p - position
        r = np.linalg.norm(x, axis=-1)
        if light_kind(light) == "spot":
            cos_theta = np.clip(np.sum(x * light_axis(light), axis=-1) / r, -1.0, 1.0)
            factor = factor * spot_profile(np.arccos(cos_theta), _field(light, "cutoff_angle", 20.0),
                                           _field(light, "beam_width"))
        if _field(light, "falloff", "none") == "inverse_square":
            factor = factor / r**2
    return factor[..., None] * colour


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
        colour = light_intensity(p, light)
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
