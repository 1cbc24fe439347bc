"""docs/examples/inverse_material.py recovers what it rendered its target with: a sphere's diffuse colour
and its light's colour, to 1e-3, from a start 0.3 away, by Adam on Renderer.backward's gradients."""

import importlib.util
from pathlib import Path

import numpy as np

EXAMPLE = Path(__file__).resolve().parents[2] / "docs" / "examples" / "inverse_material.py"


def test_the_inverse_rendering_example_recovers_the_true_values():
    spec = importlib.util.spec_from_file_location("inverse_material", EXAMPLE)
    example = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(example)
    found = example.recover(verbose=False)
    for name, value in found.items():
        assert np.abs(value - np.asarray(example.TRUE[name])).max() < 1e-3, (name, value)
        assert np.abs(np.asarray(example.START[name]) - np.asarray(example.TRUE[name])).max() > 0.2  # a real start
