"""Clamped and mirrored textures against Mitsuba's bitmap with the same wrap mode: a glTF quad whose
uv runs from -1 to 2, lit by a point light, every pixel as the accuracy suite checks it."""

import pytest

import warprt

from accuracy.harness import check
from formats.test_texture_wrap import quad_gltf, quad_scene_doc, write_texture
from scenekit import write_scene

pytestmark = pytest.mark.accuracy


@pytest.mark.parametrize("mode", ["clamp", "mirror"])
def test_wrapped_texture_matches_mitsuba(tmp_path, mode):
    write_texture(tmp_path / "t.png")
    quad_gltf(tmp_path / "q.gltf", (mode, mode))
    doc = quad_scene_doc("q.gltf", lights=[{"position": [1.0, 2.0, 5.0], "color": [0.8, 0.8, 0.8]}],
                         ambient=[0.2, 0.2, 0.2])
    write_scene(tmp_path, doc, "s.toml")
    check(f"texture_wrap_{mode}", warprt.load_scene(tmp_path / "s.toml"))
