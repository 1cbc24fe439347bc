"""warprt.torch.render(..., edges=...) (issue 38): the image's backward passes ``edges`` on to
Renderer.backward, so each tensor's .grad is backward(edges=True)'s, silhouettes' and shadows' edges
included, with the interior derivative (edges=False) as the control; its default is backward's own; and
backward's refusal of edges (a curved mirror's reflections) reaches loss.backward()'s caller as its one
line, no .grad written."""

from __future__ import annotations

import inspect
from dataclasses import replace

import numpy as np
import pytest
import torch

import warprt
import warprt.torch
from warprt import SceneError
from warprt.image import MAX_GLASS_DEPTH

from .scenes import HEIGHT, WIDTH, ball

# A pose, a light and the camera: each moves the ball's silhouette or its shadow's edge.
NAMES = ("objects.ball.translation", "lights.0.position", "camera.eye")


def one_level() -> warprt.Scene:
    """ball() with primary rays only: no mirror rays, so edges=True is the whole derivative."""
    s = ball()
    return replace(s, render=replace(s.render, max_depth=1))


def deep_curved_mirror() -> warprt.Scene:
    """ball() with the ball itself a mirror (smooth, curved: the crossings' edges) traced past the ray levels the
    crossings follow (MAX_GLASS_DEPTH): what it reflects there has no edge term."""
    s = ball()
    return replace(s, materials={**s.materials, "ball": replace(s.materials["ball"], reflectivity=(0.3,) * 3)},
                   render=replace(s.render, max_depth=MAX_GLASS_DEPTH + 1))


@pytest.fixture(scope="module")
def d_image():
    return np.random.default_rng(3).standard_normal((HEIGHT, WIDTH, 3)).astype(np.float32)


def torch_grads(d_image, **edges) -> dict:
    """Each tensor's .grad after loss.backward(), loss = sum(d_image * image) through warprt.torch.render."""
    with warprt.Renderer(one_level()) as r:
        params = {n: torch.tensor(r.params[n], requires_grad=True) for n in NAMES}
        (torch.from_numpy(d_image) * warprt.torch.render(r, params, **edges)).sum().backward()
    return {n: t.grad.numpy() for n, t in params.items()}


def backwards(d_image, **edges) -> dict:
    with warprt.Renderer(one_level()) as r:
        r.render(grad=True)
        return r.backward(d_image, wrt=list(NAMES), **edges)


def test_with_edges_the_grads_are_backwards_with_edges(d_image):
    found, expected, interior = torch_grads(d_image, edges=True), backwards(d_image, edges=True), backwards(d_image, edges=False)
    for name in NAMES:
        g = expected[name]
        np.testing.assert_allclose(found[name], g.astype(np.float32), rtol=1e-6, atol=1e-6 * np.abs(g).max(),
                                   err_msg=name)
        # The control: the edges' term is a real part of each gradient here.
        assert np.abs(interior[name] - g).max() > 0.05 * np.abs(g).max(), name


def test_without_edges_the_grads_are_the_interior_derivative(d_image):
    found, expected = torch_grads(d_image, edges=False), backwards(d_image, edges=False)
    for name in NAMES:
        np.testing.assert_allclose(found[name], expected[name].astype(np.float32), rtol=1e-6,
                                   atol=1e-6 * np.abs(expected[name]).max(), err_msg=name)


def test_the_default_is_backwards_own():
    def default(f):
        return inspect.signature(f).parameters["edges"].default

    assert default(warprt.torch.render) == default(warprt.Renderer.backward)


def test_backwards_refusal_of_edges_reaches_the_caller_in_one_line():
    """A mirroring ball traced past MAX_GLASS_DEPTH ray levels: what it reflects there has no edge term."""
    with warprt.Renderer(deep_curved_mirror()) as r:
        t = torch.tensor(r.params["objects.ball.translation"], requires_grad=True)
        image = warprt.torch.render(r, {"objects.ball.translation": t}, edges=True)
        with pytest.raises(SceneError) as e:
            image.sum().backward()
        assert "\n" not in str(e.value) and str(e.value).startswith("backward(): edges: ")
        assert t.grad is None
        warprt.torch.render(r, {"objects.ball.translation": t}, edges=False).sum().backward()  # the control
        assert t.grad is not None
