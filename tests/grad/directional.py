"""Directional derivatives of a loss sum(weights * image) by central finite differences of warprt's own
forward render, for the gradient tests: the parameters moved through r.params (as a user would), along a
random direction, and the pixels where a step crosses an edge (a shadow's, a silhouette's, a texel's
seam) masked out, as issue 30 asks: there the differences at h and at h/2 disagree (a jump J gives
J / 2h and J / h), and the gradient, which holds each ray's face and visibility fixed, has no term for
it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

import warprt


@dataclass
class Directional:
    direction: dict  # {name: the step of each parameter per unit of t}
    fd: float  # d loss / dt at t = 0 over the kept pixels, central differences at h / 2
    mask: np.ndarray  # (H, W, 1): 1 where the differences at h and h / 2 agree
    masked: float  # the share of pixels masked out

    def gradient(self, grads: dict) -> float:
        """The same directional derivative from backward()'s gradients (of the masked weights)."""
        return float(sum((np.asarray(grads[n], np.float64) * v).sum() for n, v in self.direction.items()))

    def error(self, grads: dict) -> float:
        """|gradient - fd| / |fd|."""
        return abs(self.gradient(grads) - self.fd) / abs(self.fd)


def random_direction(scene, names, seed: int = 3, rel: float = 1.0, only=None) -> dict:
    """A random step for each named parameter, scaled to its size (max(|value|, 1) * rel per component;
    ``only``: {name: boolean mask of the parameter's shape} to move only some components)."""
    r = warprt.Renderer(scene)
    rng = np.random.default_rng(seed)
    out = {}
    for name in names:
        value = np.asarray(r.params[name], np.float64)
        u = rng.standard_normal(value.shape) * max(float(np.abs(value).max()), 1.0) * rel
        if only and name in only:
            u = u * only[name]
        out[name] = u
    r.close()
    return out


def directional(scene, direction: dict, weights, h: float = 1e-3, tol: float = 0.05, same_faces: bool = False,
                start: dict | None = None, **options) -> Directional:
    """Central differences of sum(weights * image) along ``direction`` (parameters set to value + t step),
    at t = +-h and +-h/2; pixels where the two disagree by more than ``tol`` of their size (plus a floor
    for float32 noise) are masked out. With ``same_faces`` (one camera ray a pixel), so are the pixels
    whose camera ray meets another triangle at any of the steps (the face AOV): a crease between two
    triangles of a smooth mesh crossing the ray bends the differences (a kink, not a jump) by less than
    the h / h/2 test sees. ``start``: r.params values set first, the point the differences are taken at
    (a pose, which lives in the Renderer rather than the scene)."""
    r = warprt.Renderer(scene, **({"aovs": ("face",)} if same_faces else {}), **options)
    r.params.update(start or {})
    base = {n: np.asarray(r.params[n], np.float64) for n in direction}
    faces = []

    def image(t: float) -> np.ndarray:
        r.params.update({n: base[n] + t * v for n, v in direction.items()})
        result = r.render()
        if same_faces:
            faces.append(result.aovs["face"])
        return result.image.astype(np.float64)

    wide = (image(h) - image(-h)) / (2 * h)
    narrow = (image(h / 2) - image(-h / 2)) / h
    if same_faces:
        image(0.0)
    r.close()
    floor = 1e-4 * max(np.abs(narrow).max(), 1e-12) + 4e-7 / h
    keep = np.all(np.abs(wide - narrow) <= tol * np.maximum(np.abs(wide), np.abs(narrow)) + floor, axis=-1)
    for f in faces:
        keep &= np.reshape(f == faces[-1], keep.shape)
    mask = keep[..., None].astype(np.float32)
    fd = float((weights.astype(np.float64) * mask * narrow).sum())
    return Directional(direction, fd, mask, 1.0 - float(keep.mean()))


def backward_masked(scene, weights, d: Directional, start: dict | None = None, **options) -> dict:
    """backward() of the masked weights, for the parameters of ``d`` (at ``start``, as directional's)."""
    r = warprt.Renderer(scene, **options)
    r.params.update(start or {})
    r.render(grad=True)
    g = r.backward((weights * d.mask).astype(np.float32), wrt=list(d.direction), edges=False)
    r.close()
    return g
