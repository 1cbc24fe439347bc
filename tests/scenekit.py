"""Small scenes for tests, written as the dicts a TOML scene file parses to."""

from __future__ import annotations

import copy

from warprt.scene import scene_from_dict

# A camera on the +z axis looking at the origin: the image plane is parallel to z = 0.
FRONT_CAMERA = {"eye": [0.0, 0.0, 5.0], "center": [0.0, 0.0, 0.0], "up": [0.0, 1.0, 0.0],
                "fovy": 60.0, "near": 1.0, "width": 64, "height": 48}


def make_scene(objects, materials=None, lights=(), camera=None, **render):
    doc = {
        "camera": {**FRONT_CAMERA, **(camera or {})},
        "render": {"ambient": [0.0, 0.0, 0.0], "background": [0.0, 0.0, 0.0], "max_depth": 1, **render},
        "lights": [dict(l) for l in lights],
        "materials": copy.deepcopy(materials or {}),
        "objects": [dict(o) for o in objects],
    }
    return scene_from_dict(doc, "<test>")


# A material that shows only its ambient term: with C_amb = 1 a hit pixel is exactly ka.
MARKER = {"ka": [1.0, 1.0, 1.0], "kd": [0.0, 0.0, 0.0]}
