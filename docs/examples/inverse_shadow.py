"""Recover a point light's position from the shadow it casts, and from nothing else: Adam in PyTorch on
warprt's gradients, edges included (warprt.torch.render(..., edges=True)).

    python docs/examples/inverse_shadow.py                # both runs, the light's error as it falls
    python docs/examples/inverse_shadow.py --figure benchmarks/figures/inverse_shadow.png

A lamp hangs near the centre c of a spherical room of radius R, above a plate. The room's wall is lit head-on
from everywhere: at a wall point p of inward normal n = (c - p) / R, with the light at c + e, the cosine of
the seed's model (falloff "none": no 1/r^2) is n . L = (R + n . e) / |c + e - p| = 1 - |e_perp|^2 / (2 R^2) + ...,
e_perp the part of e across n. From the start to the true position |e| <= 0.53 (0.27 R), so the lit wall's
colour kd C (n . L) stays within 3.5% of kd C there (measured on the image: n . L >= 0.978 at the true
position, >= 0.967 at the start), and its derivative in the light's position is at most |e| / R^2 (0.13 per
unit) of kd C, nothing at the centre. The plate is black (kd 0, lit by the ambient term only), so its shading does not depend on the
light either. What moves with the light is its shadow on the wall: where the shadow lies and how large it is
(the light's height over the plate), which is all three of its coordinates.

The interior derivative (edges=False) holds every shadow ray's answer fixed, so all it sees is the wall's
faint shading: at the start it is 3% of the whole gradient's size and points almost the other way (cosine
-0.96), and Adam, which scales every step to the same size, follows it away. With edges=True the boundary term
of the shadow's edges (where a shadow ray from the wall grazes the plate's outline) is nearly all of the
gradient, and the light comes home in a few dozen steps.

The target is warprt's own render at the true position (the same samples: the loss is 0 there). The loss is
0.5 * sum((image - target)^2); Adam's step is constant for the first half of the steps, then shrinks to 5%.
"""

from __future__ import annotations

import argparse
import time

import numpy as np
import torch

import edges_figure  # this folder's: the figure both edge examples draw
import warprt
import warprt.torch

LIGHT = "lights.0.position"
RADIUS = 2.0  # the room's; the scene's size is its diameter
TRUE = np.array([0.3, 0.2, -0.2])
START = np.array([-0.1, 0.5, 0.15])  # 0.61 from TRUE: 15% of the scene's size
RATE = 0.05  # Adam's step, in the scene's units


def scene(width: int = 96, height: int = 72, spp: int = 4) -> warprt.Scene:
    """A smooth spherical room (an icosphere of 5,120 faces), a square black plate hung in it, one point light
    at TRUE; the camera inside, looking down at the plate and its shadow."""
    return warprt.load_dict({
        "camera": {"eye": [0.0, 1.0, 1.6], "center": [0.0, -1.6, -0.2], "fovy": 60, "width": width, "height": height},
        "render": {"ambient": [0.2] * 3, "max_depth": 1, "spp": spp},
        "lights": [{"position": TRUE.tolist(), "color": [0.8, 0.8, 0.8]}],  # falloff "none": the seed's model
        "materials": {"wall": {"kd": [0.7, 0.65, 0.6], "ka": [1.0, 1.0, 1.0]},
                      "plate": {"kd": [0.0, 0.0, 0.0], "ka": [0.5, 0.25, 0.1]}},
        "objects": [{"name": "room", "shape": "sphere", "subdivisions": 4, "smooth": True, "scale": RADIUS,
                     "material": "wall"},
                    {"name": "plate", "shape": "plane", "size": [0.5, 0.5], "translate": [0.0, -0.9, 0.0],
                     "rotate": [0, 30, 0], "material": "plate"}]})


def light_error(position) -> float:
    """The light's distance from TRUE in % of the scene's size (the room's diameter)."""
    return float(np.linalg.norm(np.asarray(position) - TRUE) / (2 * RADIUS) * 100)


def fit(r: warprt.Renderer, target: np.ndarray, edges: bool, steps: int) -> dict:
    """Adam from START towards ``target``, through warprt.torch.render with ``edges``. Returns the loss and the
    light's error per step, the position found and its error, the seconds taken and the last image."""
    position = torch.tensor(START, requires_grad=True)
    adam = torch.optim.Adam([position], lr=RATE)
    half = steps // 2
    shrink = torch.optim.lr_scheduler.LambdaLR(adam, lambda k: 0.05 ** (max(0, k - half) / (steps - half)))
    goal = torch.from_numpy(target)
    losses, errors, start = [], [], time.perf_counter()
    for _ in range(steps):
        adam.zero_grad()
        loss = 0.5 * ((warprt.torch.render(r, {LIGHT: position}, edges=edges) - goal) ** 2).sum()
        loss.backward()
        losses.append(loss.item())
        errors.append(light_error(position.detach().numpy()))
        adam.step()
        shrink.step()
    seconds = time.perf_counter() - start
    with torch.no_grad():
        result = warprt.torch.render(r, {LIGHT: position}).numpy()
    found = position.detach().numpy()
    return {"loss": losses, "error": errors, "found": found, "final": light_error(found), "seconds": seconds,
            "result": result}


def interior_share(r: warprt.Renderer, target: np.ndarray) -> float:
    """|the interior derivative| / |the whole derivative| of the loss in the light's position, at START."""
    r.params[LIGHT] = START
    image = r.render(grad=True).image
    interior, whole = (r.backward(image - target, wrt=[LIGHT], edges=edges)[LIGHT] for edges in (False, True))
    return float(np.linalg.norm(interior) / np.linalg.norm(whole))


def recover(steps: int = 60, width: int = 96, height: int = 72, spp: int = 4, verbose: bool = True) -> dict:
    """The target at TRUE, then the fit with edges=True and with edges=False from START.
    Returns {"target", "start", "interior_share", True: run, False: run}."""
    with warprt.Renderer(scene(width, height, spp)) as r:
        out = {"target": r.render().image}
        r.params[LIGHT] = START
        out["start"] = r.render().image
        out["interior_share"] = interior_share(r, out["target"])
        for edges in (True, False):
            run = out[edges] = fit(r, out["target"], edges, steps)
            if verbose:
                print(f"edges={edges}: {steps} steps in {run['seconds']:.1f} s, the light {run['final']:.2f}% of "
                      f"the scene's size away (started {run['error'][0]:.1f}%), at {np.round(run['found'], 3)}")
    if verbose:
        print(f"at the start the interior derivative is {out['interior_share']:.1%} of the whole gradient's size")
    return out


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--figure", help="write the figure (target, start, results, loss and error curves) here")
    ap.add_argument("--steps", type=int, default=60, help="Adam steps of each run")
    ap.add_argument("--size", type=int, nargs=2, default=(96, 72), metavar=("WIDTH", "HEIGHT"))
    ap.add_argument("--spp", type=int, default=4, help="samples a pixel (k x k)")
    args = ap.parse_args(argv)
    out = recover(args.steps, *args.size, args.spp)
    if args.figure:
        images = {"target": out["target"], "start": out["start"], "edges=True": out[True]["result"],
                  "edges=False": out[False]["result"]}
        edges_figure.figure(args.figure, "A point light's position from its shadow alone, by Adam through "
                            "warprt.torch.render", images, out, "0.5 sum (image - target)^2",
                            ("the light, % of the scene's size",))
    return out


if __name__ == "__main__":
    main()
