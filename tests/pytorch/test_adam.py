"""docs/python.md's PyTorch example, run as written (issue 38): torch.optim.Adam on warprt.torch.render's
gradients recovers a ball's kd and its light's colour from a target image warprt rendered, which the start
is far from."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import torch

import warprt

from .scenes import ball

DOC = Path(__file__).resolve().parents[2] / "docs" / "python.md"
TRUE = {"materials.ball.kd": [0.7, 0.25, 0.1], "lights.0.color": [0.9, 0.8, 0.6]}


def example() -> str:
    """The first code block of the page's PyTorch section."""
    section = DOC.read_text().split("\n## PyTorch\n", 1)[1].split("\n## ", 1)[0]
    return re.search(r"^```\n(.*?)^```", section, re.S | re.M).group(1)


def error(kd, color) -> float:
    """The largest difference from the true values."""
    return max(float(np.abs(np.asarray(kd) - TRUE["materials.ball.kd"]).max()),
               float(np.abs(np.asarray(color) - TRUE["lights.0.color"]).max()))


def test_adam_recovers_a_colour_and_a_light_from_a_rendered_target():
    scene = ball(48, 36)
    with warprt.Renderer(scene) as r:
        r.params.update(TRUE)
        target = torch.from_numpy(r.render().image)
    run = {"scene": scene, "target": target}
    exec(example(), run)
    start = error([0.4] * 3, [0.5] * 3)  # the example's start
    found = error(run["kd"].detach().numpy(), run["color"].detach().numpy())
    assert found < 0.02 < start, (found, start)
    run["r"].close()
