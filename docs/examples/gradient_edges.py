"""Where warprt's derivative of an image and a finite difference of it part ways: at the edges that move.

    python docs/examples/gradient_edges.py --figure benchmarks/figures/gradient_edges.png

A ball on a floor under a point light; the parameter is the light's x. Per pixel, the derivative of the
pixel's brightness (R + G + B) from Renderer.backward (one call per pixel, d_image that pixel's weights)
beside central differences of the forward render at a step of 0.1. They agree everywhere the step moves
no edge; along the ball's shadow's edge the difference jumps (a pixel goes from lit to shadowed: a finite
change over a small step), and the derivative, which holds each shadow ray's answer fixed, has no term
there: the boundary term of a Reynolds-transport renderer (Mitsuba's direct_projective, for area lights).
"""

from __future__ import annotations

import argparse

import numpy as np

import warprt

NAME = "lights.0.position"
STEP = 0.1


def scene(width: int = 96, height: int = 72) -> warprt.Scene:
    return warprt.load_dict({
        "camera": {"eye": [0.0, 2.5, 5.0], "center": [0.0, 0.4, 0.0], "width": width, "height": height},
        "render": {"ambient": [0.2] * 3, "max_depth": 1},
        "lights": [{"position": [1.5, 3.5, 2.5], "color": [0.9, 0.8, 0.6]}],
        "materials": {"floor": {"kd": [0.6, 0.6, 0.6]}, "ball": {"kd": [0.75, 0.3, 0.15], "ks": [0.5] * 3,
                                                                 "shininess": 20}},
        "objects": [{"shape": "plane", "size": [6.0, 6.0], "material": "floor"},
                    {"shape": "sphere", "subdivisions": 3, "smooth": True, "translate": [0.0, 0.8, 0.0], "scale": 0.8,
                     "material": "ball"}]})


def derivative_images(width: int = 96, height: int = 72) -> dict:
    """The image, the derivative of each pixel's R + G + B with respect to the light's x (backward, per
    pixel), and the central difference of the same at STEP."""
    r = warprt.Renderer(scene(width, height))
    image = r.render(grad=True).image
    interior = np.zeros((height, width))
    weights = np.zeros((height, width, 3), np.float32)
    for y in range(height):
        for x in range(width):
            weights[y, x] = 1.0
            interior[y, x] = r.backward(weights, wrt=[NAME], edges=False)[NAME][0]
            weights[y, x] = 0.0
    position = np.asarray(r.params[NAME], np.float64)
    shifted = []
    for sign in (1.0, -1.0):
        r.params[NAME] = position + sign * np.array([STEP, 0.0, 0.0])
        shifted.append(r.render().image.astype(np.float64).sum(-1))
    r.close()
    return {"image": image, "interior": interior, "fd": (shifted[0] - shifted[1]) / (2 * STEP)}


def figure(d: dict, path: str):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    scale = float(np.percentile(np.abs(d["interior"]), 99.5)) or 1.0
    part = np.abs(d["fd"] - d["interior"]) > 0.05 * scale + 1e-3
    fig, axes = plt.subplots(1, 4, figsize=(15, 3.3))
    axes[0].imshow(np.clip(d["image"], 0, 1) ** (1 / 2.2))
    axes[0].set_title("image")
    for ax, key, title in ((axes[1], "interior", "backward: d(R+G+B)/d light x"),
                           (axes[2], "fd", f"central difference, step {STEP}")):
        ax.imshow(d[key], cmap="RdBu_r", vmin=-scale, vmax=scale)
        ax.set_title(title)
    axes[3].imshow(np.where(part, 1.0, 0.0), cmap="gray_r")
    axes[3].set_title(f"where they part: {part.mean():.1%} of pixels")
    for ax in axes:
        ax.axis("off")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return part


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--figure", default="gradient_edges.png")
    args = ap.parse_args()
    d = derivative_images()
    part = figure(d, args.figure)
    keep = ~part
    print(f"pixels where they part: {part.mean():.1%}; elsewhere the largest difference "
          f"{np.abs(d['fd'] - d['interior'])[keep].max():.2e} (derivatives up to {np.abs(d['interior']).max():.2f})")
    print(f"wrote {args.figure}")
