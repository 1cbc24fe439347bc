"""The examples that only edges make work (issue 38), run as docs/gradients.md runs them: Adam through
warprt.torch.render recovers, with edges=True, docs/examples/inverse_pose.py the Cornell box's short box's pose
from Mitsuba's image to 1% of the box's size and 1 degree, and docs/examples/inverse_shadow.py a point light's
position from its shadow alone to 1% of the scene's size, each from a start well off; the same runs with
edges=False (the interior derivative) end far from it."""

import importlib.util
import sys
from pathlib import Path

import numpy as np
import pytest

EXAMPLES = Path(__file__).resolve().parents[2] / "docs" / "examples"


def example(name: str):
    """docs/examples/<name>.py as a module, its folder on the path as when it runs as a script."""
    sys.path.insert(0, str(EXAMPLES))
    try:
        spec = importlib.util.spec_from_file_location(name, EXAMPLES / f"{name}.py")
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
    finally:
        sys.path.remove(str(EXAMPLES))
    return module


@pytest.mark.slow
def test_the_pose_example_recovers_the_box_with_edges_and_not_without():
    pose = example("inverse_pose")
    out = pose.main([])
    start = out[True]["error"][0]
    assert start[0] > 10 and start[1] > 10  # a real start: 10% of the box and 10 degrees off
    translation, degrees = out[True]["final"]
    assert translation < 1.0 and degrees < 1.0, out[True]["final"]
    translation, degrees = out[False]["final"]
    assert translation > 10 or degrees > 10, out[False]["final"]  # the interior derivative alone goes astray
    assert pose.closeness(out[True]["result"], out["target"]) < 0.03  # warprt's model is Mitsuba's image


def test_the_shadow_example_recovers_the_light_with_edges_and_not_without():
    shadow = example("inverse_shadow")
    out = shadow.main([])
    assert out[True]["error"][0] > 10  # a real start: 10% of the scene's size off
    assert out[True]["final"] < 1.0, out[True]["found"]
    assert out[False]["final"] > 10, out[False]["found"]
    assert out["interior_share"] < 0.1  # the receiver's shading is as good as constant: the shadow is the signal
    assert np.abs(out[True]["result"] - out["target"]).mean() < 1e-3
