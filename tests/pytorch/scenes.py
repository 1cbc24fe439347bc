"""The small scenes the PyTorch tests render."""

from __future__ import annotations

import warprt

WIDTH, HEIGHT = 24, 18


def ball(width: int = WIDTH, height: int = HEIGHT) -> warprt.Scene:
    """A smooth ball on a slightly mirroring floor, two lights: materials, lights, vertices and the camera
    each change the image (two ray levels)."""
    return warprt.load_dict({
        "camera": {"eye": [0.0, 2.0, 5.0], "center": [0.0, 0.6, 0.0], "width": width, "height": height},
        "render": {"ambient": [0.1] * 3, "max_depth": 2},
        "lights": [{"position": [2.0, 4.0, 3.0]}, {"position": [-3.0, 3.0, 2.0], "color": [0.3, 0.3, 0.4]}],
        "materials": {"floor": {"kd": [0.5, 0.5, 0.5], "reflectivity": [0.2] * 3},
                      "ball": {"kd": [0.5] * 3, "ks": [0.4] * 3, "shininess": 30}},
        "objects": [{"name": "floor", "shape": "plane", "size": [8.0, 8.0], "material": "floor"},
                    {"name": "ball", "shape": "sphere", "subdivisions": 2, "smooth": True, "translate": [0.0, 0.8, 0.0],
                     "scale": 0.8, "material": "ball"}]})


def lamp() -> warprt.Scene:
    """A floor under an emitting square (an area light whose vertices backward() holds fixed)."""
    return warprt.load_dict({
        "camera": {"eye": [0.0, 2.0, 5.0], "center": [0.0, 0.5, 0.0], "width": 16, "height": 12},
        "render": {"light_samples": 4},
        "materials": {"floor": {"kd": [0.5, 0.5, 0.5]}, "glow": {"kd": [0.1] * 3, "emission": [4.0, 3.5, 3.0]}},
        "objects": [{"name": "floor", "shape": "plane", "size": [8.0, 8.0], "material": "floor"},
                    {"name": "lamp", "shape": "triangles", "material": "glow", "faces": [[0, 1, 2], [0, 2, 3]],
                     "vertices": [[-0.5, 1.5, -0.5], [0.5, 1.5, -0.5], [0.5, 1.5, 0.5], [-0.5, 1.5, 0.5]]}]})
