"""The inverse-rendering examples recover what they rendered their targets with, by Adam on
Renderer.backward's gradients: docs/examples/inverse_material.py a sphere's diffuse colour and its light's
colour, to 1e-3, from a start 0.3 away; docs/examples/inverse_rendering.py a texture, a material and a
light's position and colour."""

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


RENDERING = EXAMPLE.parent / "inverse_rendering.py"


def test_the_inverse_rendering_example_recovers_texture_material_and_light():
    """docs/examples/inverse_rendering.py as docs/gradients.md runs it (300 Adam steps, 96 x 72): the floor's
    texels (the median's error: the texels the balls hide keep their start), the balls' ks and the light's
    colour and position, each from a start 0.3 to 1.0 away, to a tenth of that or better."""
    spec = importlib.util.spec_from_file_location("inverse_rendering", RENDERING)
    example = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(example)
    run = example.recover(verbose=False)
    found, true, start = run["found"], example.TRUE, example.START
    texels = lambda a: float(np.median(np.abs(a - true["materials.floor.kd_texture"]).max(-1)))  # noqa: E731
    assert texels(found["materials.floor.kd_texture"]) < 0.05 < 0.25 < texels(start["materials.floor.kd_texture"])
    for name, within in (("materials.ball.ks", 0.1), ("lights.0.color", 0.05), ("lights.0.position", 0.2)):
        assert np.abs(found[name] - true[name]).max() < within, (name, found[name])
        assert np.abs(start[name] - true[name]).max() > 3 * within  # a real start
    assert run["loss"][-1] < run["loss"][0] / 500
