"""No render returns NaN or Inf: the renderer checks its own output (warprt.image.check_finite), and
adversarial but valid scenes render finite images."""

import copy

import numpy as np
import pytest
import warp as wp

import warprt
from scenekit import make_scene

from stability.probes import record
from warprt.image import check_finite



@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_check_finite_rejects_a_non_finite_pixel(bad):
    image = np.zeros((4, 5, 3), np.float32)
    check_finite(image)  # a finite image passes
    image[2, 3, 1] = bad
    image[3, 0, 0] = bad
    with pytest.raises(RuntimeError, match=r"2 non-finite pixels \(first at row 2, column 3\)"):
        check_finite(image)


def test_render_refuses_to_return_a_non_finite_image(monkeypatch):
    """render() runs the check on what the kernel wrote: a NaN smuggled into the image buffer
    (here by a wrapped launch) becomes an error, not a picture."""
    real = wp.launch

    def poisoned(kernel, dim, inputs, *args, **kwargs):
        real(kernel, dim, inputs, *args, **kwargs)
        image = next((a for a in inputs if isinstance(a, wp.array) and a.dtype == wp.vec3), None)
        if image is not None:  # a rasterization launch has no image among its inputs
            image.fill_(wp.vec3(np.nan, 0.0, 0.0))

    monkeypatch.setattr(wp, "launch", poisoned)
    scene = make_scene([{"shape": "sphere", "material": "m"}], {"m": {"kd": [0.5] * 3}}, [{"position": [2, 3, 4]}])
    with pytest.raises(RuntimeError, match="non-finite pixels"):
        warprt.render(scene)


MIRROR = {"kd": [0.1] * 3, "ks": [0.5] * 3, "shininess": 0.0, "reflectivity": 1.0}
WALL = {"shape": "plane", "size": [50.0, 50.0], "rotate": [90.0, 0.0, 0.0], "material": "w"}
CASES = {
    # A light exactly on the surface it lights, at a vertex and at an interior point.
    "light at a vertex": ([WALL], {"w": {"kd": [0.7] * 3, "ks": [0.3] * 3}}, [{"position": [25.0, 25.0, 0.0]}], {}, {}),
    "light on the surface": ([WALL], {"w": {"kd": [0.7] * 3}}, [{"position": [0.1, 0.2, 0.0]}], {}, {}),
    # The light at the eye, and the eye on the surface's vertex.
    "light at the eye": ([WALL], {"w": {"kd": [0.7] * 3}}, [{"position": [0.0, 0.0, 5.0]}], {}, {}),
    "eye at a vertex": ([{"shape": "sphere", "material": "w"}], {"w": {"kd": [0.7] * 3}}, [{"position": [0, 3, 3]}],
                        {"eye": [0.0, 1.0, 0.0], "center": [0.0, 0.0, 0.0], "up": [1.0, 0.0, 0.0]}, {}),
    # Exponents 0 (r.v^0 = 1, and 0^0 must not be NaN) and huge.
    "shininess 0": ([WALL], {"w": {"kd": [0.2] * 3, "ks": [1.0] * 3, "shininess": 0.0}}, [{"position": [0, 0, 3]}], {}, {}),
    "shininess 1e6": ([WALL], {"w": {"ks": [1.0] * 3, "shininess": 1e6}}, [{"position": [0, 0, 3]}], {}, {}),
    # Lossless facing mirrors for 1024 levels, and a mildly amplifying one that stays in range.
    "kr = 1 for 1024 levels": ([WALL, {**WALL, "translate": [0, 0, 10]}], {"w": MIRROR}, [{"position": [0, 1, 4]}], {}, {"max_depth": 1024}),
    "kr = 1.05 for 200 levels": ([WALL, {**WALL, "translate": [0, 0, 10]}], {"w": {**MIRROR, "reflectivity": 1.05}},
                                 [{"position": [0, 1, 4]}], {}, {"max_depth": 200}),
    # Extreme but valid cameras.
    "fovy 1e-6": ([WALL], {"w": {"kd": [0.7] * 3}}, [{"position": [0, 0, 3]}], {"fovy": 1e-6}, {}),
    "fovy 179.999": ([WALL], {"w": {"kd": [0.7] * 3}}, [{"position": [0, 0, 3]}], {"fovy": 179.999}, {}),
    "near 1e-18": ([WALL], {"w": {"kd": [0.7] * 3}}, [{"position": [0, 0, 3]}], {"near": 1e-18}, {}),
    # Tiny and huge scenes, and one near the edge of float32 reach (scene.MAX_REACH = 1e12).
    "scene 1e-12 across": ([{"shape": "sphere", "radius": 1e-12, "material": "w"}], {"w": {"kd": [0.7] * 3}},
                           [{"position": [1e-12, 2e-12, 3e-12]}], {"eye": [0, 0, 5e-12], "near": 1e-12}, {}),
    "scene 1e11 across": ([{"shape": "sphere", "radius": 1e11, "material": "w"}], {"w": {"kd": [0.7] * 3}},
                          [{"position": [1e11, 2e11, 3e11]}], {"eye": [0, 0, 5e11]}, {}),
    "object 8e11 away": ([{"shape": "sphere", "radius": 1e11, "translate": [0, 0, -8e11], "material": "w"}],
                         {"w": {"kd": [0.7] * 3}}, [{"position": [0, 8e11, 0]}], {"fovy": 20.0}, {}),
    # Only degenerate triangles, and nothing at all.
    "zero-area triangles only": ([{"shape": "triangles", "vertices": [[0, 0, 0], [1, 1, 1], [2, 2, 2], [0, 1, 0]],
                                   "faces": [[0, 1, 2], [3, 3, 3], [0, 0, 1]], "material": "w"}], {"w": {"kd": [0.7] * 3}},
                                 [{"position": [0, 0, 3]}], {}, {}),
    "empty scene": ([], {}, [], {}, {}),
}


# Cases whose lit object must show: the scale and reach cases, not only a finite image.
SEEN = {"scene 1e-12 across", "scene 1e11 across", "object 8e11 away", "light at the eye", "eye at a vertex", "fovy 1e-6"}


@pytest.mark.parametrize("name", list(CASES))
def test_adversarial_scenes_render_finite(name):
    objects, materials, lights, camera, render = copy.deepcopy(CASES[name])
    scene = make_scene(objects, materials, lights, camera=camera, ambient=[0.1] * 3, background=[0.2] * 3, **render)
    image, stats = warprt.render(scene, threads=2)
    seen = float((image.max(-1) > 0.2 + 1e-6).mean())  # pixels brighter than the background
    record(f"finite/{name}", {"finite": bool(np.isfinite(image).all()), "max": float(image.max()), "lit_fraction": seen})
    assert np.isfinite(image).all()
    if name in SEEN:
        assert seen > 0.01, "the scene's object should be visible and lit"
