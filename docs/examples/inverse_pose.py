"""Recover where the Cornell box's short box stands, and how it is turned, from one image of it that Mitsuba
rendered: Adam in PyTorch on warprt's gradients, edges included (warprt.torch.render(..., edges=True)).

    python docs/examples/inverse_pose.py                # both runs, the pose's error as it falls
    python docs/examples/inverse_pose.py --figure benchmarks/figures/inverse_pose.png

The target is scenes/cornell_box.xml with the short box moved by TRUE's translation and turned by its rotation
(objects.small-box.translation and .rotation in r.params: an offset, and a rotation vector about the box's
centre), rendered by Mitsuba's own `direct` integrator, converged, through the file's camera with a box filter:
Mitsuba's box is given warprt's posed vertices, so both renderers agree on what the pose means. warprt starts
from the file's pose, 15% of the box's size and 15 degrees away, and fits all six numbers.

A box of one colour that moves changes the image almost only at its outline and its shadow's: the interior
derivative (edges=False) sees the shading of the pixels the box already covers, not the pixels its edges
cross, so it goes astray; with edges=True the boundary terms of its silhouette, of the edges where it hides
the walls and of its soft shadow (each of the area light's sample points a hard shadow) bring it home.

The loss is 0.5 * sum((min(image, 1) - min(target, 1))^2), the images as displayed: the light's own pixels
(radiance 18) are white in both, and the row its edge cuts, where warprt's 4 x 4 samples and Mitsuba's
converged mean cover it differently, would otherwise be most of the loss, constant and blind to the box.
A blurred image pyramid was tried and dropped: it converged no faster, the start's box already overlapping
the target's. Adam's step is constant for the first half of the steps, then shrinks to 5% of it.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np
import torch

import edges_figure  # this folder's: the figure both edge examples draw
import warprt
import warprt.torch

SCENE = Path(__file__).resolve().parents[2] / "scenes" / "cornell_box.xml"
BOX = "small-box"
POSE = (f"objects.{BOX}.translation", f"objects.{BOX}.rotation")
TRUE = {POSE[0]: np.array([0.07, 0.0, -0.06]), POSE[1]: np.array([0.0, 0.26, 0.0])}  # 0.26 rad: 15 degrees
RATE = {POSE[0]: 0.015, POSE[1]: 0.04}  # Adam's step: in the scene's units, and radians


def scene(size: int = 64, light_samples: int = 16, spp: int = 16) -> warprt.Scene:
    """The file at size x size pixels, its area light as light_samples points, spp samples a pixel: at the
    true pose within SSIM 0.998 of Mitsuba's converged image at 64 x 64."""
    return warprt.load_scene(SCENE, {"camera.width": size, "camera.height": size,
                                     "render.light_samples": light_samples, "render.spp": spp})


def mitsuba_target(vertices: np.ndarray, size: int, spp: int = 4096) -> np.ndarray:
    """Mitsuba's `direct` render of the file with the box's vertices set to ``vertices`` (warprt's posed ones):
    (size, size, 3) linear RGB, the mean of spp samples a pixel over a box filter, as warprt's pixels are."""
    import drjit as dr
    import mitsuba as mi

    mi.set_variant("llvm_ad_rgb")  # vectorised on every core (warprt's XML reader leaves the slow scalar_rgb set)
    file = mi.load_file(str(SCENE), optimize=False)  # optimize=False: each shape its own mesh, named by its id
    params = mi.traverse(file)
    params[f"{BOX}.vertex_positions"] = dr.ravel(mi.Point3f(np.ascontiguousarray(vertices.T, np.float32)))
    params.update()  # the same 24 vertices in the same order as warprt read them from the file
    camera = mi.traverse(file.sensors()[0])
    sensor = mi.load_dict({
        "type": "perspective", "fov_axis": "x", "fov": float(np.ravel(camera["x_fov"])[0]),
        "to_world": mi.ScalarTransform4f(np.array(camera["to_world"].matrix, np.float64).reshape(4, 4)),
        "film": {"type": "hdrfilm", "width": size, "height": size, "rfilter": {"type": "box"}}})
    passes = max(1, spp // 1024)  # 1024 samples a pass keep the LLVM wavefront small
    direct = mi.load_dict({"type": "direct"})
    return np.mean([np.array(mi.render(file, sensor=sensor, integrator=direct, spp=spp // passes, seed=k))[..., :3]
                    for k in range(passes)], 0)


def rotation(w) -> np.ndarray:
    """The rotation matrix of rotation vector w (Rodrigues' formula)."""
    angle = np.linalg.norm(w)
    k = np.cross(np.eye(3), w / angle) if angle > 0 else np.zeros((3, 3))
    return np.eye(3) + np.sin(angle) * k + (1 - np.cos(angle)) * k @ k


def pose_error(translation, rotation_vector, box_size: float) -> tuple[float, float]:
    """(the translation's error in % of the box's size, the angle in degrees between the rotations)."""
    moved = np.linalg.norm(np.asarray(translation) - TRUE[POSE[0]]) / box_size * 100
    turn = rotation(np.asarray(rotation_vector)) @ rotation(TRUE[POSE[1]]).T
    return float(moved), float(np.degrees(np.arccos(np.clip((np.trace(turn) - 1) / 2, -1, 1))))


def displayed(image: torch.Tensor) -> torch.Tensor:
    """The image as a display shows it: the light's own pixels (radiance 18) white."""
    return image.clamp(max=1.0)


def closeness(image: np.ndarray, target: np.ndarray) -> float:
    """The mean |difference| of the images as displayed, over the target's mean."""
    a, b = np.minimum(image, 1.0), np.minimum(target, 1.0)
    return float(np.abs(a - b).mean() / b.mean())


def fit(r: warprt.Renderer, target: np.ndarray, edges: bool, steps: int, box_size: float) -> dict:
    """Adam from the file's pose (0, 0) towards ``target``, through warprt.torch.render with ``edges``.
    Returns the loss and the pose's error per step, the pose found, the seconds taken and the last image."""
    pose = {n: torch.zeros(3, dtype=torch.float64, requires_grad=True) for n in POSE}
    adam = torch.optim.Adam([{"params": [pose[n]], "lr": RATE[n]} for n in POSE])
    half = steps // 2
    shrink = torch.optim.lr_scheduler.LambdaLR(adam, lambda k: 0.05 ** (max(0, k - half) / (steps - half)))
    goal = displayed(torch.from_numpy(target.astype(np.float32)))
    losses, errors, start = [], [], time.perf_counter()
    for _ in range(steps):
        adam.zero_grad()
        image = warprt.torch.render(r, pose, edges=edges)
        loss = 0.5 * ((displayed(image) - goal) ** 2).sum()
        loss.backward()
        losses.append(loss.item())
        errors.append(pose_error(*(pose[n].detach().numpy() for n in POSE), box_size))
        adam.step()
        shrink.step()
    found = {n: pose[n].detach().numpy() for n in POSE}
    seconds = time.perf_counter() - start
    with torch.no_grad():
        result = warprt.torch.render(r, pose).numpy()
    return {"loss": losses, "error": errors, "found": found, "final": pose_error(*found.values(), box_size),
            "seconds": seconds, "result": result}


def recover(steps: int = 60, size: int = 64, light_samples: int = 16, spp: int = 16,
            mitsuba_spp: int = 4096, verbose: bool = True) -> dict:
    """The Mitsuba target, then the fit with edges=True and with edges=False from the same start.
    Returns {"target", "start", "model" (warprt at the true pose), "box_size", True: run, False: run}."""
    with warprt.Renderer(scene(size, light_samples, spp)) as r:
        box_size = float(np.ptp(r.params[f"objects.{BOX}.vertices"][:, 1]))  # its height: a cube's edge
        start = r.render().image
        r.params.update(TRUE)
        out = {"target": mitsuba_target(r.params[f"objects.{BOX}.vertices"], size, mitsuba_spp),
               "start": start, "model": r.render().image, "box_size": box_size}
        for edges in (True, False):
            run = out[edges] = fit(r, out["target"], edges, steps, box_size)
            if verbose:
                print(f"edges={edges}: {steps} steps in {run['seconds']:.1f} s, translation off by "
                      f"{run['final'][0]:.2f}% of the box, rotation by {run['final'][1]:.2f} degrees "
                      f"(started {run['error'][0][0]:.1f}%, {run['error'][0][1]:.1f} degrees)")
    return out


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--figure", help="write the figure (target, start, results, loss and error curves) here")
    ap.add_argument("--steps", type=int, default=60, help="Adam steps of each run")
    ap.add_argument("--size", type=int, default=64, help="the image's width and height in pixels")
    ap.add_argument("--light-samples", type=int, default=16, help="points on the area light (render.light_samples)")
    ap.add_argument("--spp", type=int, default=16, help="warprt's samples a pixel (k x k)")
    ap.add_argument("--mitsuba-spp", type=int, default=4096, help="Mitsuba's samples a pixel for the target")
    args = ap.parse_args(argv)
    out = recover(args.steps, args.size, args.light_samples, args.spp, args.mitsuba_spp)
    for name, image in (("the true pose", out["model"]), ("the pose found", out[True]["result"])):
        print(f"warprt at {name} against Mitsuba's target: mean |difference| "
              f"{closeness(image, out['target']):.2%} of the target's mean")
    if args.figure:  # the images, then both runs' loss and the pose's error per step
        images = {"target (Mitsuba, direct)": out["target"], "start": out["start"],
                  "edges=True": out[True]["result"], "edges=False": out[False]["result"]}
        edges_figure.figure(args.figure, "The short box's pose from Mitsuba's image, by Adam through "
                            "warprt.torch.render", images, out, "0.5 sum (min(image, 1) - min(target, 1))^2",
                            ("translation, % of the box", "rotation, degrees"))
    return out


if __name__ == "__main__":
    main()
