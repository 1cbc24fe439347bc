"""The figure of the examples whose fits only edges make work (inverse_pose.py, inverse_shadow.py): the target,
the start and what the fits with edges=True and edges=False ended at, then both runs' loss and error per step."""

from __future__ import annotations

import numpy as np


def figure(path: str, title: str, images: dict, runs: dict, loss: str, errors: tuple[str, ...]):
    """``images``: {panel title: linear RGB image}; ``runs``: {edges (True, False): {"loss": per step, "error": per
    step a number, or a tuple of one per name in ``errors``}}; ``loss``: the loss's formula. The goal (an error of
    1 in each unit) is a line on the error plot."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(images) + 2, figsize=(3.2 * len(images) + 9, 3.4),
                             gridspec_kw={"width_ratios": [1] * len(images) + [1.4, 1.4]})
    for ax, (name, image) in zip(axes, images.items()):
        ax.imshow(np.clip(image, 0, 1) ** (1 / 2.2))
        ax.set_title(name)
        ax.axis("off")
    curves, error_axes = axes[-2:]
    for edges, style in ((True, "-"), (False, "--")):
        steps = np.arange(1, len(runs[edges]["loss"]) + 1)
        curves.semilogy(steps, runs[edges]["loss"], style, color="C0" if edges else "C1", label=f"edges={edges}")
        per_step = np.array(runs[edges]["error"], np.float64).reshape(len(steps), -1)
        for i, name in enumerate(errors):
            error_axes.semilogy(steps, per_step[:, i], style, color=f"C{2 * i}", label=f"{name}, edges={edges}")
    curves.set_title(loss, fontsize=9)
    error_axes.axhline(1.0, color="k", lw=0.8)
    error_axes.set_title("error (goal: below 1)")
    for ax in (curves, error_axes):
        ax.set_xlabel("Adam step")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7)
    fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)
    print(f"wrote {path}")
