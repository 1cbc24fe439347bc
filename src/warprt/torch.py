"""warprt inside PyTorch (``pip install 'warprt[torch]'``): render(renderer, params) is a Renderer's frame as a
torch.Tensor, differentiable in each parameter tensor that requires grad (render(grad=...) and backward()).

    import warprt.torch
    image = warprt.torch.render(r, {"materials.ball.kd": kd, "lights.0.color": color})   # (H, W, 3) float32
    loss = 0.5 * ((image - target) ** 2).sum()
    loss.backward()                        # kd.grad, color.grad: what r.backward gives for image - target

What is copied, and why. The scene keeps its parameters as float64 on the host (r.params), so each tensor's
values are read into it (a CUDA tensor's come back to the host). The frame's image is a NumPy array on the host
(the trace reads it back: the finite-pixel check, the stats), so on the CPU the tensor returned is a view of it
(torch.from_numpy) and on a GPU one copy to the device. The image's adjoint goes to backward() as it is where it
can: on the CPU a NumPy view of a float32 tensor, copied only where torch hands an expanded or strided one (the
adjoint of image.sum() is); where it and the Renderer are on CUDA, a wp.array over its memory (wp.from_torch),
which backward reads back to the host itself. Each gradient comes back as backward's float64 NumPy array, then cast to its tensor's
dtype and moved to its device.
"""

from __future__ import annotations

import inspect

import numpy as np
import torch

from ._warp import wp
from .errors import ArgumentError, SceneError
from .image.grad_params import not_differentiated
from .image.renderer import Renderer

FUNCTION = "warprt.torch.render"
# Renderer.backward's own default, read from it: the image's backward passes the same unless told otherwise.
BACKWARD_EDGES = inspect.signature(Renderer.backward).parameters["edges"].default


def render(renderer, params: dict, edges: bool = BACKWARD_EDGES) -> torch.Tensor:
    """The next frame of ``renderer`` (a warprt.Renderer) with ``params`` ({r.params name: torch.Tensor of that
    parameter's shape}) set, as an (H, W, 3) float32 tensor on the tensors' device (the renderer's without any).
    Where a tensor requires grad (and torch records gradients), the frame is rendered with grad=[those names]
    and the image's grad_fn hands its adjoint to renderer.backward(d_image, wrt=those names, edges=edges): each
    tensor's .grad gets its gradient, in its dtype, on its device; with ``edges`` (Renderer.backward's default
    unless given), the boundary term of silhouettes and shadows' edges included, and backward's refusal of it
    (mirrors, glass, a checker texture, a spot's hard cone) raised by loss.backward() as backward's one line.
    Else a plain frame, nothing recorded.

    One ArgumentError line, naming the parameter, before anything is set or rendered: a name r.params does not
    have, a value that is not a tensor or not of the parameter's shape, tensors on two devices, and a tensor
    that requires grad for a parameter backward() does not differentiate (backward's own words). The image's
    backward must run on the frame that made it: where the renderer has rendered again before loss.backward(),
    one line says so rather than give the other frame's gradient."""
    names, tensors = list(params), list(params.values())
    dtypes, device = _checked(renderer, names, tensors)
    wrt = tuple(n for n, t in zip(names, tensors) if t.requires_grad) if torch.is_grad_enabled() else ()
    for name in wrt:
        why = not_differentiated(renderer.scene, name)
        if why is not None:
            raise ArgumentError(FUNCTION, name, why)
    # As r.params holds each (float32 texels, float64 the rest): a CPU tensor of that dtype is read as a view.
    renderer.params.update({n: t.detach().to("cpu", dtypes[n]).numpy() for n, t in zip(names, tensors)})
    if not wrt:
        return _image(renderer.render().image, device)
    return _GradFrame.apply(renderer, tuple(names), wrt, bool(edges), device, *tensors)


def _checked(renderer, names: list, tensors: list) -> tuple[dict, torch.device]:
    """The torch dtype r.params holds each parameter in, and the tensors' one device (the renderer's where
    there are none), each name and shape checked against r.params (one ArgumentError naming the parameter)."""
    known = renderer.params
    devices, dtypes = {}, {}
    for name, t in zip(names, tensors):
        try:
            value = known[name]
        except SceneError as e:  # an unknown name, with r.params' guess at the one meant
            raise ArgumentError(FUNCTION, str(name), e.message) from None
        expected, dtypes[name] = value.shape, torch.float32 if value.dtype == np.float32 else torch.float64
        if not isinstance(t, torch.Tensor):
            raise ArgumentError(FUNCTION, name, f"expected a torch.Tensor of shape {expected}, got {type(t).__name__}")
        if tuple(t.shape) != expected:
            raise ArgumentError(FUNCTION, name, f"expected shape {expected}, got {tuple(t.shape)}")
        devices.setdefault(t.device, name)
    if len(devices) > 1:
        (first, a), (other, b) = list(devices.items())[:2]
        raise ArgumentError(FUNCTION, b, f"on {other}, {a} on {first}: give every tensor on one device")
    return dtypes, next(iter(devices), torch.device(renderer.options.device))


def _image(image: np.ndarray, device: torch.device) -> torch.Tensor:
    """The frame's image (a fresh float32 NumPy array, the renderer keeps no reference) as a tensor on ``device``."""
    return torch.from_numpy(image).to(device)


def _adjoint(d_image: torch.Tensor, renderer_device: str):
    """The image's adjoint as backward() takes it: a wp.array over a CUDA tensor's memory, else a NumPy view."""
    d = d_image.detach().to(torch.float32).contiguous()
    if d.is_cuda and str(renderer_device).startswith("cuda"):
        return wp.from_torch(d)
    return d.cpu().numpy()


class _GradFrame(torch.autograd.Function):
    """A grad frame of a renderer whose parameters render() has set from ``tensors`` (inputs here so that
    autograd reaches them): the image forward, backward()'s gradients for the names in ``wrt`` back (with the
    edges' boundary term where ``edges``)."""

    @staticmethod
    def forward(ctx, renderer, names, wrt, edges, device, *tensors):
        image = renderer.render(grad=list(wrt)).image  # grad=[names]: a named reflectivity of 0 recorded too
        ctx.renderer, ctx.names, ctx.wrt, ctx.edges, ctx.frame = renderer, names, wrt, edges, renderer.grad_frame
        ctx.like = [(t.shape, t.dtype, t.device) for t in tensors]
        return _image(image, device)

    @staticmethod
    @torch.autograd.function.once_differentiable
    def backward(ctx, d_image):
        r = ctx.renderer
        if r.grad_frame != ctx.frame:
            raise ArgumentError(FUNCTION, ", ".join(ctx.wrt), "the renderer has rendered another frame (or was "
                                "closed) since this image, so backward() would differentiate that frame: call "
                                "loss.backward() before the next render, or give each image its own Renderer")
        grads = r.backward(_adjoint(d_image, r.options.device), wrt=list(ctx.wrt), edges=ctx.edges)
        out = [None if name not in grads else _gradient(grads[name], *like) for name, like in zip(ctx.names, ctx.like)]
        return (None, None, None, None, None, *out)


def _gradient(g, shape, dtype, device) -> torch.Tensor:
    """backward()'s float64 gradient (an array, or a NumPy scalar for a () parameter) as its tensor's."""
    return torch.from_numpy(np.ascontiguousarray(g, np.float64)).reshape(shape).to(device=device, dtype=dtype)
