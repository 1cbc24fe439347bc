"""warprt.torch.render's refusals (issue 38): a bad name, a bad shape, a value that is not a tensor, tensors on
two devices, a parameter backward() does not differentiate given with requires_grad, and an image's backward
after the renderer has rendered another frame; each one ArgumentError line naming the parameter, the first
ones before anything is set or rendered."""

from __future__ import annotations

import numpy as np
import pytest
import torch

import warprt
import warprt.torch
from warprt import SceneError

from .scenes import ball, lamp


def refusal(r, params: dict) -> SceneError:
    """The one-line error warprt.torch.render(r, params) raises, checked to leave the renderer as it was."""
    scene, frame = r.scene, r.grad_frame
    with pytest.raises(SceneError) as e:
        warprt.torch.render(r, params)
    assert "\n" not in str(e.value)
    assert r.scene is scene and r.grad_frame == frame and r.geometry is None  # nothing set, nothing rendered
    return e.value


@pytest.fixture
def r():
    with warprt.Renderer(ball()) as renderer:
        yield renderer


def test_an_unknown_name_is_named_with_the_one_meant(r):
    e = refusal(r, {"materials.ball.kd": torch.ones(3), "materials.bal.kd": torch.ones(3)})
    assert str(e) == ("warprt.torch.render(): materials.bal.kd: unknown parameter "
                      "(did you mean 'materials.ball.kd'?)")


def test_a_wrong_shape_is_named_with_the_shape_expected(r):
    e = refusal(r, {"lights.0.position": torch.ones(4)})
    assert str(e) == "warprt.torch.render(): lights.0.position: expected shape (3,), got (4,)"
    e = refusal(r, {"objects.ball.vertices": torch.ones(3)})
    assert str(e).startswith("warprt.torch.render(): objects.ball.vertices: expected shape (")


def test_a_value_that_is_not_a_tensor_is_named(r):
    e = refusal(r, {"camera.fovy": 40.0})
    assert str(e) == "warprt.torch.render(): camera.fovy: expected a torch.Tensor of shape (), got float"


def test_tensors_on_two_devices_are_named(r):
    e = refusal(r, {"materials.ball.kd": torch.ones(3), "camera.eye": torch.ones(3, device="meta")})
    assert str(e) == ("warprt.torch.render(): camera.eye: on meta, materials.ball.kd on cpu: "
                      "give every tensor on one device")


def test_a_parameter_backward_does_not_differentiate_is_refused_in_backwards_words():
    with warprt.Renderer(lamp()) as r:
        name = "objects.lamp.vertices"
        vertices = torch.tensor(r.params[name], requires_grad=True)
        e = refusal(r, {name: vertices})
        r.render(grad=True)
        with pytest.raises(SceneError) as backwards:
            r.backward(np.zeros((12, 16, 3), np.float32), wrt=[name])
        assert (e.argument, e.template) == (name, backwards.value.template)
        assert str(e).startswith(f"warprt.torch.render(): {name}: the object is an area light")
        warprt.torch.render(r, {name: vertices.detach()})  # the control: without requires_grad it renders


def test_backward_after_another_frame_is_refused(r):
    kd = torch.tensor(r.params["materials.ball.kd"], requires_grad=True)
    image = warprt.torch.render(r, {"materials.ball.kd": kd})
    r.render()  # the frame the image came from is no longer backward()'s
    with pytest.raises(SceneError) as e:
        image.sum().backward()
    assert str(e.value).startswith("warprt.torch.render(): materials.ball.kd: the renderer has rendered another frame")
    assert "\n" not in str(e.value) and kd.grad is None
    warprt.torch.render(r, {"materials.ball.kd": kd}).sum().backward()  # the control: backward before the next frame
    assert kd.grad is not None


def test_backward_after_another_grad_frame_is_refused(r):
    """A second image of the same renderer replaces the first one's record: only the latest can go back."""
    kd = torch.tensor(r.params["materials.ball.kd"], requires_grad=True)
    first = warprt.torch.render(r, {"materials.ball.kd": kd})
    second = warprt.torch.render(r, {"materials.ball.kd": kd * 0.5})
    with pytest.raises(SceneError, match="materials.ball.kd: the renderer has rendered another frame"):
        first.sum().backward()
    second.sum().backward()
    assert kd.grad is not None
