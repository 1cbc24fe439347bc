"""Inverse rendering with warprt's gradients: recover a sphere's diffuse colour and its light's colour from
one photograph of them (here rendered, so the answer is known).

    python docs/examples/inverse_material.py

The loss is 0.5 * sum((image - target)^2), so its derivative with respect to the image is image - target:
Renderer.backward(image - target, wrt=[...]) gives its gradient for the parameters, named as r.params
names them, and r.params takes the updated values for the next frame (Adam, a few lines of NumPy).
"""

from __future__ import annotations

import numpy as np

import warprt

TRUE = {"materials.ball.kd": [0.7, 0.25, 0.1], "lights.0.color": [0.9, 0.8, 0.6]}
START = {"materials.ball.kd": [0.4, 0.4, 0.4], "lights.0.color": [0.5, 0.5, 0.5]}


def scene() -> warprt.Scene:
    return warprt.load_dict({
        "camera": {"eye": [0.0, 2.0, 5.0], "center": [0.0, 0.6, 0.0], "width": 64, "height": 48},
        "render": {"ambient": [0.1] * 3, "max_depth": 1},
        "lights": [{"position": [2.0, 4.0, 3.0]}, {"position": [-3.0, 3.0, 2.0], "color": [0.3, 0.3, 0.4]}],
        "materials": {"floor": {"kd": [0.5, 0.5, 0.5]}, "ball": {"kd": [0.5] * 3, "ks": [0.4] * 3, "shininess": 30}},
        "objects": [{"shape": "plane", "size": [8.0, 8.0], "material": "floor"},
                    {"shape": "sphere", "subdivisions": 3, "smooth": True, "translate": [0.0, 0.8, 0.0], "scale": 0.8,
                     "material": "ball"}]})


def recover(steps: int = 150, rate: float = 0.05, verbose: bool = True) -> dict:
    """Adam on the parameters of START, its step shrinking 3% a step, until the render matches the target;
    returns the values found."""
    r = warprt.Renderer(scene())
    r.params.update(TRUE)
    target = r.render().image
    r.params.update(START)
    names = list(START)
    m = {n: np.zeros(3) for n in names}
    v = {n: np.zeros(3) for n in names}
    for step in range(1, steps + 1):
        image = r.render(grad=True).image
        loss = 0.5 * float(((image - target) ** 2).sum())
        grads = r.backward(image - target, wrt=names)
        values = {}
        for n in names:
            m[n] = 0.9 * m[n] + 0.1 * grads[n]
            v[n] = 0.999 * v[n] + 0.001 * grads[n] ** 2
            step_size = rate * 0.97 ** step * (m[n] / (1 - 0.9 ** step)) / (np.sqrt(v[n] / (1 - 0.999 ** step)) + 1e-8)
            values[n] = np.maximum(r.params[n] - step_size, 0.0)
        r.params.update(values)
        if verbose and (step % 25 == 0 or step == 1):
            print(f"step {step:3d}  loss {loss:.3e}  " + "  ".join(f"{n} {np.round(r.params[n], 3)}" for n in names))
    return {n: r.params[n] for n in names}


if __name__ == "__main__":
    found = recover()
    for name, value in found.items():
        print(f"{name}: found {np.round(value, 4)}, true {TRUE[name]}")
