"""Float64 closed forms for glass, written from the Fresnel equations and Snell's law, independently
of both renderers: the reflectance, Snell's and the critical angle, the slab's series of internal
reflections, and a ray followed through a given sequence of planar faces.

Conventions (as the renderers'): n is the surface's outward (winding) normal; a ray d enters when
d.n < 0. eta is the glass's index, air is 1. Directions are unit vectors.
"""

from __future__ import annotations

import math

import numpy as np


def fresnel(cos_i, eta_i, eta_t):
    """Unpolarised reflectance from medium eta_i into eta_t, cos_i = |cos| of the incidence angle:
    F = (r_s^2 + r_p^2) / 2, r_s = (n_i c_i - n_t c_t)/(n_i c_i + n_t c_t), r_p = (n_t c_i - n_i c_t)/(n_t c_i + n_i c_t);
    1 past the critical angle (sin_t >= 1). Vectorised."""
    cos_i = np.abs(np.asarray(cos_i, np.float64))
    sin_t2 = (eta_i / eta_t) ** 2 * np.maximum(0.0, 1.0 - cos_i**2)
    tir = sin_t2 >= 1.0
    cos_t = np.sqrt(np.maximum(0.0, 1.0 - sin_t2))
    with np.errstate(divide="ignore", invalid="ignore"):
        rs = (eta_i * cos_i - eta_t * cos_t) / (eta_i * cos_i + eta_t * cos_t)
        rp = (eta_t * cos_i - eta_i * cos_t) / (eta_t * cos_i + eta_i * cos_t)
    F = 0.5 * (rs**2 + rp**2)
    return np.where(tir, 1.0, np.where(cos_i == 0.0, 1.0, F))


def normal_incidence(eta):
    """F at normal incidence: ((eta - 1) / (eta + 1))^2."""
    return ((eta - 1.0) / (eta + 1.0)) ** 2


def critical_angle(eta):
    """asin(1 / eta): past it a ray inside glass (eta > 1) is totally reflected."""
    return math.asin(1.0 / eta)


def snell_angle(theta_i, eta_i, eta_t):
    """theta_t with eta_i sin theta_i = eta_t sin theta_t; nan past the critical angle."""
    s = eta_i / eta_t * np.sin(theta_i)
    return np.where(np.abs(s) <= 1.0, np.arcsin(np.clip(s, -1, 1)), np.nan)


def refract_dir(d, n, eta):
    """Snell in vector form at a surface with outward normal n of a glass of index eta, or None (TIR).
    Returns (t, F, entering)."""
    d = np.asarray(d, np.float64)
    entering = float(d @ n) < 0.0
    nn = n if entering else -n  # normal on the incident side
    e_i, e_t = (1.0, eta) if entering else (eta, 1.0)
    c = -float(d @ nn)
    F = float(fresnel(c, e_i, e_t))
    r = e_i / e_t
    k = 1.0 - r * r * (1.0 - c * c)
    if k <= 0.0:
        return None, 1.0, entering
    t = r * d + (r * c - math.sqrt(k)) * nn
    return t / np.linalg.norm(t), F, entering


def reflect_dir(d, n):
    r = d - 2.0 * float(d @ n) * n
    return r / np.linalg.norm(r)


def slab_series(theta, eta, kt, sigma, thickness, max_depth=None):
    """A slab of two parallel faces, seen at incidence theta. Returns (T, R, shift):
    T = sum_n (1-F)^2 kt^2 F^(2n) a^(2n+1) (rays leaving through the back, n internal double bounces),
    R = F + sum_n (1-F)^2 kt^2 F^(2n+1) a^(2n+2) (rays leaving back through the front), a = exp(-sigma d / cos theta_t),
    each path kept only when it fits in max_depth ray levels (the leaving ray's level counted: a back-side
    path with n double bounces reaches the object behind at level 3 + 2n, a front-side one misses at 4 + 2n;
    None: the infinite series, T = (1-F)^2 kt^2 a / (1 - F^2 a^2)).
    shift = d sin(theta - theta_t) / cos theta_t, the lateral offset of the first transmitted ray."""
    theta = np.asarray(theta, np.float64)
    F = fresnel(np.cos(theta), 1.0, eta)
    tt = snell_angle(theta, 1.0, eta)
    a = np.exp(-np.asarray(sigma, np.float64) * thickness / np.cos(tt))
    kt2 = np.asarray(kt, np.float64) ** 2
    base = (1.0 - F) ** 2 * kt2
    if max_depth is None:
        T = base * a / (1.0 - F**2 * a**2)
        R = F + base * F * a**2 / (1.0 - F**2 * a**2)
    else:
        zero = np.zeros(np.broadcast(base, a).shape)
        T = zero + sum((base * F ** (2 * n) * a ** (2 * n + 1) for n in range(max_depth) if 3 + 2 * n <= max_depth), zero)
        R = zero + (F if max_depth >= 2 else 0.0) + sum((base * F ** (2 * n + 1) * a ** (2 * n + 2)
                                                        for n in range(max_depth) if 4 + 2 * n <= max_depth), zero)
    shift = thickness * np.sin(theta - tt) / np.cos(tt)
    return T, R, shift


class Face:
    """A planar convex polygon (the face of a glass object) with its outward normal."""

    def __init__(self, corners, normal=None):
        self.c = np.asarray(corners, np.float64)
        n = np.cross(self.c[1] - self.c[0], self.c[2] - self.c[0]) if normal is None else np.asarray(normal, float)
        self.n = n / np.linalg.norm(n)
        edges = np.roll(self.c, -1, axis=0) - self.c
        inward = np.cross(self.n, edges)
        self._inward = inward / np.linalg.norm(inward, axis=1, keepdims=True)

    def hit(self, o, d):
        """(t, p, edge distance) of rays o + t d, one (3,) or many (N, 3), on the face's plane; the
        edge distance is < 0 outside the polygon, t is inf for a ray parallel to the plane."""
        o, d = np.asarray(o, np.float64), np.asarray(d, np.float64)
        den = d @ self.n
        with np.errstate(divide="ignore", invalid="ignore"):
            t = np.where(den != 0.0, ((self.c[0] - o) @ self.n) / np.where(den != 0.0, den, 1.0), np.inf)
            p = o + t[..., None] * d
            m = np.min(np.einsum("...ij,ij->...i", p[..., None, :] - self.c, self._inward), axis=-1)
        m = np.where(np.isfinite(t), m, -np.inf)
        return (float(t), p, float(m)) if t.ndim == 0 else (t, p, m)


def plane_paths(o, d, steps, eta, kt, sigma):
    """Follow rays o + t d, many at once ((N, 3), or one origin for all), through a known sequence of
    faces, each ("T") refracted or ("R") reflected at, in float64. Absorption applies between
    consecutive faces of the sequence, inside the glass. Returns (weights (N, 3), final origins, final
    directions, smallest edge distances, valid): not valid where the sequence is impossible (a
    refraction past the critical angle, or a face behind the ray)."""
    d = np.atleast_2d(np.asarray(d, np.float64))
    o = np.broadcast_to(np.asarray(o, np.float64), d.shape).copy()
    kt, sigma = np.asarray(kt, float), np.asarray(sigma, float)
    n_rays = len(d)
    w, margin = np.ones((n_rays, 3)), np.full(n_rays, np.inf)
    valid, inside = np.ones(n_rays, bool), np.zeros(n_rays, bool)
    for face, action in steps:
        t, p, m = face.hit(o, d)
        valid &= np.isfinite(t) & (t > 0)
        margin = np.minimum(margin, m)
        w = np.where(inside[:, None], w * np.exp(-sigma * np.where(valid, t, 0.0)[:, None]), w)
        cos = d @ face.n
        entering = cos < 0.0
        nn = np.where(entering[:, None], face.n, -face.n)  # the normal on the incident side
        e_i, e_t = np.where(entering, 1.0, eta), np.where(entering, eta, 1.0)
        c = np.abs(cos)
        F = fresnel(c, e_i, e_t)
        if action == "T":
            r = e_i / e_t
            k = 1.0 - r**2 * (1.0 - c**2)
            valid &= k > 0.0
            tdir = r[:, None] * d + (r * c - np.sqrt(np.maximum(k, 0.0)))[:, None] * nn
            w = w * (1.0 - F)[:, None] * kt
            d = tdir / np.linalg.norm(tdir, axis=1, keepdims=True)
            inside = entering
        else:
            w = w * F[:, None]
            r = d - 2.0 * cos[:, None] * face.n
            d = r / np.linalg.norm(r, axis=1, keepdims=True)
            inside = ~entering
        o = np.where(valid[:, None], p, o)
    return w, o, d, margin, valid


def plane_path(o, d, steps, eta, kt, sigma):
    """plane_paths for one ray: (weight RGB, final origin, final direction, smallest edge distance), or
    None where the sequence is impossible."""
    w, o, d, margin, valid = plane_paths(o, d, steps, eta, kt, sigma)
    return (w[0], o[0], d[0], float(margin[0])) if valid[0] else None
