"""Inverse rendering with warprt's gradients: recover a floor's texture, the balls' specular colour and a
light's position and colour from one photograph of them (here rendered, so the answer is known).

    python docs/examples/inverse_rendering.py                     # prints the loss as it falls
    python docs/examples/inverse_rendering.py --figure benchmarks/figures/inverse_rendering.png

The loss is 0.5 * sum((image - target)^2), so its derivative with respect to the image is image - target:
Renderer.backward(image - target, wrt=[...]) gives the gradient of every parameter named, as r.params names
them, and r.params takes the updated values for the next frame (Adam, a few lines of NumPy). The balls' known grey kd, seen from two
sides of the light, fixes its position and colour (the floor alone could trade its texture against the
light's colour, an unknown kd against it too);
the texels the balls hide from the camera get no gradient and stay as they started.
"""

from __future__ import annotations

import argparse
from dataclasses import replace

import numpy as np

import warprt
from warprt.scene import Material, Texture

TEXELS = 8  # the floor texture's width and height


def true_texture() -> np.ndarray:
    """An 8 x 8 RGB pattern: colour ramps across, a darker band down the middle."""
    u, v = np.meshgrid(np.linspace(0, 1, TEXELS), np.linspace(0, 1, TEXELS))
    image = np.stack([0.3 + 0.6 * u, 0.3 + 0.5 * v, 0.8 - 0.5 * u * v], -1)
    image[:, 3:5] *= 0.6
    return image.astype(np.float32)


TRUE = {"materials.floor.kd_texture": true_texture(), "materials.ball.ks": np.array([0.7, 0.55, 0.3]),
        "lights.0.color": np.array([0.9, 0.8, 0.6]), "lights.0.position": np.array([1.5, 3.5, 2.5])}
START = {"materials.floor.kd_texture": np.full((TEXELS, TEXELS, 3), 0.5, np.float32),
         "materials.ball.ks": np.array([0.3, 0.3, 0.3]), "lights.0.color": np.array([0.5, 0.5, 0.5]),
         "lights.0.position": np.array([0.5, 3.0, 2.0])}
RATE = {"materials.floor.kd_texture": 0.04, "materials.ball.ks": 0.03, "lights.0.color": 0.03,
        "lights.0.position": 0.25}  # Adam's step per parameter, in its own units


def scene(width: int = 96, height: int = 72) -> warprt.Scene:
    s = warprt.load_dict({
        "camera": {"eye": [0.0, 2.5, 5.0], "center": [0.0, 0.4, 0.0], "width": width, "height": height},
        "render": {"ambient": [0.25] * 3, "max_depth": 1},
        "lights": [{"position": [1.0, 3.0, 2.0]}, {"position": [-3.0, 3.0, 2.0], "color": [0.3, 0.3, 0.4]}],
        "materials": {"floor": {"kd_texture": {"checker": [[1, 1, 1], [0.5, 0.5, 0.5]]}},  # its uvs; replaced below
                      "ball": {"kd": [0.6] * 3, "ks": [0.5] * 3, "shininess": 12}},
        "objects": [{"shape": "plane", "size": [6.0, 6.0], "material": "floor"},
                    *({"shape": "sphere", "subdivisions": 3, "smooth": True, "translate": [x, 0.6, z], "scale": 0.6,
                       "material": "ball"} for x, z in ((-1.3, 0.0), (1.2, -0.6)))]})
    materials = dict(s.materials)
    materials["floor"] = Material(kd=(1.0, 1.0, 1.0), kd_texture=Texture(image=START["materials.floor.kd_texture"]))
    return replace(s, materials=materials)


def errors(params) -> dict:
    """Each parameter's largest distance from its true value."""
    return {n: float(np.abs(np.asarray(params[n]) - TRUE[n]).max()) for n in TRUE}


def recover(steps: int = 300, width: int = 96, height: int = 72, verbose: bool = True) -> dict:
    """Adam on the parameters of START, its step shrinking 0.5% a step, until the render matches the target.
    Returns {"found": the values found, "loss": the loss per step, "target", "start", "result": images}."""
    r = warprt.Renderer(scene(width, height))
    r.params.update(TRUE)
    target = r.render().image
    r.params.update(START)
    start = r.render().image
    names = list(START)
    m = {n: np.zeros_like(START[n], np.float64) for n in names}
    v = {n: np.zeros_like(START[n], np.float64) for n in names}
    losses = []
    for step in range(1, steps + 1):
        image = r.render(grad=True).image
        losses.append(0.5 * float(((image - target) ** 2).sum()))
        grads = r.backward(image - target, wrt=names)
        values = {}
        for n in names:
            m[n] = 0.9 * m[n] + 0.1 * grads[n]
            v[n] = 0.999 * v[n] + 0.001 * grads[n] ** 2
            shift = RATE[n] * 0.995 ** step * (m[n] / (1 - 0.9 ** step)) / (np.sqrt(v[n] / (1 - 0.999 ** step)) + 1e-8)
            value = np.asarray(r.params[n], np.float64) - shift
            values[n] = value if n.endswith("position") else np.maximum(value, 0.0)  # colours stay >= 0
        r.params.update(values)
        if verbose and (step % 25 == 0 or step == 1):
            e = errors(r.params)
            print(f"step {step:3d}  loss {losses[-1]:.3e}  " + "  ".join(f"{n.split('.')[-1]} {x:.3f}" for n, x in e.items()))
    found = {n: np.asarray(r.params[n]) for n in names}
    result = r.render().image
    r.close()
    return {"found": found, "loss": losses, "target": target, "start": start, "result": result}


def figure(run: dict, path: str):
    """Target, start and result side by side, the loss curve beside them."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 4, figsize=(15, 3.2), gridspec_kw={"width_ratios": [1, 1, 1, 1.2]})
    for ax, key in zip(axes, ("target", "start", "result")):
        ax.imshow(np.clip(run[key], 0, 1) ** (1 / 2.2))
        ax.set_title(key)
        ax.axis("off")
    axes[3].semilogy(np.arange(1, len(run["loss"]) + 1), run["loss"])
    axes[3].set_xlabel("step")
    axes[3].set_ylabel("0.5 sum (image - target)^2")
    axes[3].set_title("loss")
    axes[3].grid(True, which="both", alpha=0.3)
    fig.suptitle("Recovering a floor texture, the balls' specular colour and a light's position and colour "
                 "(warprt's backward, Adam)")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--figure", help="write the figure (target, start, result, loss curve) here")
    ap.add_argument("--steps", type=int, default=300)
    args = ap.parse_args()
    out = recover(args.steps)
    for name, x in errors(out["found"]).items():
        print(f"{name}: largest error {x:.4f} (started {errors(START)[name]:.3f} away)")
    if args.figure:
        figure(out, args.figure)
        print(f"wrote {args.figure}")
