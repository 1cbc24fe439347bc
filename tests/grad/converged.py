"""Directional derivatives of a loss sum(weights * image) by central differences of the converged forward, for
the boundary term's tests (backward(edges=True)): the image at 128 x 128 samples a pixel, no pixel masked, so
that an edge or a shadow's edge moving across pixels is in the differences as it is in the box-filtered
pixel integral.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

import warprt

FD_SPP = 4096  # 64 x 64 strata (the most render.spp takes) in each quarter of a pixel


def differences(make, name: str, u: np.ndarray, weights, h: float = 4e-2, steps: int = 17, k: int = 2) -> float:
    """d sum(weights * image) / dt along u from the forward at 64 k x 64 k samples a pixel (``make(FD_SPP)`` at
    k times its width and height, each pixel the mean of its k x k): the slope at 0 of a cubic fitted by least
    squares to the loss at ``steps`` steps over [-h, h] (central, and over many steps, since the image is
    still a fine staircase in t), the mean of those at h and h / 2, which agree within 4% (else the step is
    not one the differences resolve)."""
    s = make(FD_SPP)
    width, height = s.camera.width, s.camera.height
    r = warprt.Renderer(replace(s, camera=replace(s.camera, width=k * width, height=k * height)))
    base = np.asarray(r.params[name], np.float64)

    seen = {}

    def loss(t):  # each step rendered once: half of the h / 2 steps are steps of h (the same floats)
        if t not in seen:
            r.params[name] = base + t * u
            image = r.render().image.astype(np.float64).reshape(height, k, width, k, 3).mean(axis=(1, 3))
            seen[t] = float((weights.astype(np.float64) * image).sum())
        return seen[t]

    slopes = []
    for width_h in (h, h / 2):
        ts = np.linspace(-1.0, 1.0, steps)
        slopes.append(np.polyfit(ts, [loss(t * width_h) for t in ts], 3)[-2] / width_h)
    r.close()
    assert abs(slopes[0] - slopes[1]) <= 0.04 * abs(slopes[1]), slopes
    return float(np.mean(slopes))


def gradient(make, names, weights, edges: bool, **options) -> dict:
    """backward(weights, names, edges=edges) at a grad frame of ``make()`` (Renderer ``options``)."""
    r = warprt.Renderer(make(), **options)
    r.render(grad=True)
    g = r.backward(weights, wrt=list(names), edges=edges)
    r.close()
    return g


def random_step(make, name: str, seed: int) -> np.ndarray:
    """A random direction for one parameter of ``make()``, of 0.3 a component."""
    r = warprt.Renderer(make())
    shape = np.shape(r.params[name])
    r.close()
    return np.random.default_rng(seed).standard_normal(shape) * 0.3


def check_edges_term(make, name: str, seed: int, weights, h: float, tol: float, control: float, k: int = 2):
    """backward(edges=True) along a random_step against the differences (step ``h``, ``k`` x ``k`` images a
    pixel): check_against_differences."""
    check_against_differences(make, name, random_step(make, name, seed), weights, h, tol, control, k)


def check_against_differences(make, name: str, u: np.ndarray, weights, h: float, tol: float, control: float,
                              k: int = 2):
    """edges=True along u within ``tol`` of the differences (step ``h``, ``k`` x ``k`` images a pixel), every pixel
    kept; the control: the interior derivative alone (edges=False) more than ``control`` of them off."""
    fd = differences(make, name, u, weights, h=h, k=k)
    with_edges = float((gradient(make, [name], weights, True)[name] * u).sum())
    interior = float((gradient(make, [name], weights, False)[name] * u).sum())
    assert abs(with_edges - fd) <= tol * abs(fd), (with_edges, fd)
    assert abs(interior - fd) > control * abs(fd), (interior, fd)
