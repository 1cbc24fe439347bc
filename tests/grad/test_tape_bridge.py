"""A render between two Warp programs (docs/gradients.md, "In a Warp program"): a kernel on one wp.Tape
makes a material's kd from a parameter theta, warprt renders it, a loss kernel on a second tape reads the
image; the second tape's image adjoint goes to Renderer.backward(..., arrays=True), whose wp.array goes to
the first tape's backward as kd's adjoint, giving d loss / d theta. Checked against central differences of
the whole chain in theta (warprt's forward render); the control: kd's adjoint handed as ks's gives
another theta gradient."""

from __future__ import annotations

import numpy as np
import warp as wp

import warprt

BASE = (0.9, 0.5, 0.3)
NAME = "materials.ball.kd"


@wp.kernel
def colour_of(theta: wp.array(dtype=float), base: wp.vec3, kd: wp.array(dtype=float)):
    i = wp.tid()  # kd_i = base_i * (0.5 + 0.5 tanh(theta)): a user's parametrisation
    kd[i] = base[i] * (0.5 + 0.5 * wp.tanh(theta[0]))


@wp.kernel
def squared_error(image: wp.array(dtype=float, ndim=3), target: wp.array(dtype=float, ndim=3),
                  loss: wp.array(dtype=float)):
    y, x, c = wp.tid()
    e = image[y, x, c] - target[y, x, c]
    wp.atomic_add(loss, 0, 0.5 * e * e)


def scene():
    return warprt.load_dict({
        "camera": {"eye": [0.0, 2.0, 5.0], "center": [0.0, 0.6, 0.0], "width": 24, "height": 18},
        "render": {"ambient": [0.1] * 3, "max_depth": 1},
        "lights": [{"position": [2.0, 4.0, 3.0]}],
        "materials": {"floor": {"kd": [0.5, 0.5, 0.5]}, "ball": {"kd": [0.5] * 3, "ks": [0.4] * 3, "shininess": 30}},
        "objects": [{"shape": "plane", "size": [8.0, 8.0], "material": "floor"},
                    {"shape": "sphere", "subdivisions": 2, "translate": [0.0, 0.8, 0.0], "scale": 0.8,
                     "material": "ball"}]})


def target():
    r = warprt.Renderer(scene())
    r.params[NAME] = [0.7, 0.2, 0.1]
    image = r.render().image
    r.close()
    return image


def chain(r, theta_value: float, tgt: np.ndarray, handed_as: str = NAME) -> tuple[float, float]:
    """(loss, d loss / d theta) through the two tapes and the renderer."""
    theta = wp.array([theta_value], dtype=float, requires_grad=True)
    kd = wp.zeros(3, dtype=float, requires_grad=True)
    upstream = wp.Tape()
    with upstream:
        wp.launch(colour_of, dim=3, inputs=[theta, wp.vec3(*BASE)], outputs=[kd])
    r.params[NAME] = kd.numpy()
    image = wp.array(r.render(grad=True).image, dtype=float, requires_grad=True)
    loss = wp.zeros(1, dtype=float, requires_grad=True)
    downstream = wp.Tape()
    with downstream:
        wp.launch(squared_error, dim=image.shape, inputs=[image, wp.array(tgt, dtype=float)], outputs=[loss])
    downstream.backward(loss=loss)
    g = r.backward(image.grad, wrt=[NAME, "materials.ball.ks"], arrays=True, edges=False)
    assert isinstance(g[NAME], wp.array) and g[NAME].shape == (3,)
    upstream.backward(grads={kd: g[handed_as]})
    return float(loss.numpy()[0]), float(theta.grad.numpy()[0])


def test_the_render_passes_adjoints_between_two_tapes():
    tgt = target()
    r = warprt.Renderer(scene())
    theta = 0.3
    _, dtheta = chain(r, theta, tgt)
    h = 1e-2
    fd = (chain(r, theta + h, tgt)[0] - chain(r, theta - h, tgt)[0]) / (2 * h)
    assert abs(dtheta - fd) <= 1e-3 * abs(fd), (dtheta, fd)
    _, wrong = chain(r, theta, tgt, handed_as="materials.ball.ks")  # the control
    assert abs(wrong - fd) > 0.1 * abs(fd)
    r.close()
