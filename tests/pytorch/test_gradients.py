"""warprt.torch.render's gradients (issue 38): what loss.backward() leaves in each tensor's .grad is what
Renderer.backward gives for the same d_image, in the tensor's dtype, shape and device; and, in float64, the
autograd gradient of a loss sum(w * image) along a random direction per parameter equals the central difference
of that loss through warprt.torch.render itself, the pixels an edge crosses within the step masked out as the
gradient tests mask them (tests/grad/directional.py), with a wrong d_image as the control: the interior
derivative (edges=False; test_edges.py checks edges=True, the default).

torch.autograd.gradcheck itself does not fit: it steps each element by 1e-6 and the image is float32, so its
differences would be rounding; and it would see the edges the visibility-fixed derivative has no term for.
"""

from __future__ import annotations

import numpy as np
import pytest
import torch

import warprt
import warprt.torch
from tests.grad.directional import directional, random_direction

from .scenes import HEIGHT, WIDTH, ball

# A material colour, a light's position, an object's vertices, the camera: each stepped (relative to its size,
# random_direction's rel, times h) far enough for float32's rounding to stay below TOL and short of any edge.
NAMES = ("materials.ball.kd", "lights.0.position", "objects.ball.vertices", "camera.eye")
REL = {"objects.ball.vertices": 0.1, "camera.eye": 0.3}
H = {"camera.eye": 4e-3}  # the camera tests' step; 1e-3 for the others
TOL = 1e-2


def tensors(r, dtype=torch.float32, requires_grad: bool = True) -> dict:
    """The renderer's values of NAMES as tensors."""
    return {n: torch.tensor(r.params[n], dtype=dtype, requires_grad=requires_grad) for n in NAMES}


@pytest.fixture(scope="module")
def d_image():
    return torch.from_numpy(np.random.default_rng(7).standard_normal((HEIGHT, WIDTH, 3)).astype(np.float32))


@pytest.fixture(scope="module")
def torch_grads(d_image):
    """loss.backward()'s .grad of each float32 tensor, for loss = sum(d_image * image)."""
    r = warprt.Renderer(ball())
    params = tensors(r)
    image = warprt.torch.render(r, params, edges=False)
    (d_image * image).sum().backward()
    r.close()
    return params


def test_the_grads_equal_backwards_for_the_same_d_image(d_image, torch_grads):
    r = warprt.Renderer(ball())
    r.params.update({n: t.detach().numpy() for n, t in torch_grads.items()})  # the values float32 rounded
    r.render(grad=True)
    expected = r.backward(d_image.numpy(), wrt=list(NAMES), edges=False)
    r.close()
    for name, t in torch_grads.items():
        g = expected[name]
        np.testing.assert_allclose(t.grad.numpy(), g.astype(np.float32), rtol=1e-6, atol=1e-6 * np.abs(g).max(),
                                   err_msg=name)


def test_each_grad_has_its_tensors_dtype_shape_and_device(torch_grads):
    for name, t in torch_grads.items():
        assert (t.grad.dtype, t.grad.shape, t.grad.device) == (t.dtype, t.shape, t.device), name


def test_only_the_tensors_that_require_grad_get_one():
    r = warprt.Renderer(ball())
    kd = torch.tensor(r.params["materials.ball.kd"], requires_grad=True)
    eye = torch.tensor(r.params["camera.eye"])
    warprt.torch.render(r, {"materials.ball.kd": kd, "camera.eye": eye}, edges=False).sum().backward()
    r.close()
    assert kd.grad is not None and eye.grad is None


def test_without_grad_the_frame_is_a_plain_one_of_the_same_image():
    r = warprt.Renderer(ball())
    params = tensors(r, torch.float64)  # the scene's own values
    with torch.no_grad():
        image = warprt.torch.render(r, params)
    assert not image.requires_grad and r.grad_frame is None  # nothing recorded
    np.testing.assert_array_equal(image.numpy(), warprt.render(ball()).image)
    r.close()


@pytest.fixture(scope="module")
def weights():
    return np.random.default_rng(11).standard_normal((HEIGHT, WIDTH, 3))  # signed: no pixel dominates


def loss_of(r, params: dict, w: np.ndarray) -> torch.Tensor:
    """sum(w * image) in float64, through warprt.torch.render."""
    return (torch.from_numpy(w) * warprt.torch.render(r, params, edges=False).double()).sum()


@pytest.fixture(scope="module", params=NAMES)
def along(request, weights):
    """For one parameter: a random direction u, the pixels its steps of +-h and +-h/2 leave without an edge
    (directional's mask), and the central difference at h/2 of the masked loss through warprt.torch.render."""
    name = request.param
    u = random_direction(ball(), [name], seed=5, rel=REL.get(name, 1.0))
    h = H.get(name, 1e-3)
    d = directional(ball(), u, weights, h=h)
    w = weights * d.mask
    r = warprt.Renderer(ball())
    base = torch.tensor(r.params[name], dtype=torch.float64)
    step = torch.from_numpy(u[name])
    with torch.no_grad():
        fd = (loss_of(r, {name: base + h / 2 * step}, w) - loss_of(r, {name: base - h / 2 * step}, w)).item() / h
    r.close()
    return name, step, w, fd, d.masked


def autograd_along(name: str, step: torch.Tensor, w: np.ndarray) -> float:
    """The float64 autograd gradient of sum(w * image) in ``name``, dotted with ``step``."""
    r = warprt.Renderer(ball())
    value = torch.tensor(r.params[name], dtype=torch.float64, requires_grad=True)
    loss_of(r, {name: value}, w).backward()
    r.close()
    assert value.grad.dtype == torch.float64
    return float((value.grad * step).sum())


def test_the_autograd_gradient_equals_central_differences_of_the_loss(along):
    name, step, w, fd, masked = along
    assert masked < 0.02, name
    g = autograd_along(name, step, w)
    assert abs(g - fd) <= TOL * abs(fd), (name, g, fd)


def test_a_wrong_d_image_is_not_the_differences(along):
    """The control: the loss's weights upside down give another gradient."""
    name, step, w, fd, _ = along
    g = autograd_along(name, step, w[::-1].copy())
    assert abs(g - fd) > 0.1 * abs(fd), (name, g, fd)


def test_a_reflectivity_of_0_gets_its_derivative():
    """render(grad=[the names requiring grad]): a named reflectivity of 0 has its mirror rays recorded, so its
    gradient is the mirrored colour's, as r.render(grad=[name]) then backward() give it, not a refusal."""
    name = "materials.floor.reflectivity"
    r = warprt.Renderer(ball())
    r.params[name] = [0.0, 0.0, 0.0]
    kr = torch.zeros(3, requires_grad=True)
    warprt.torch.render(r, {name: kr}).sum().backward()
    r.render(grad=[name])
    expected = r.backward(np.ones((HEIGHT, WIDTH, 3), np.float32), wrt=[name])[name]
    r.close()
    assert expected.min() > 0.0
    np.testing.assert_allclose(kr.grad.numpy(), expected.astype(np.float32), rtol=1e-6)
