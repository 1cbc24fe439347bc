"""Clamped and mirrored textures against Mitsuba's bitmap with the same wrap mode: a glTF quad whose
uv runs from -1 to 2, lit by a point light, every pixel as the accuracy suite checks it."""

import pytest

import warprt

from accuracy.harness import check
from formats.test_texture_wrap import quad_gltf, write_texture

pytestmark = pytest.mark.accuracy


@pytest.mark.parametrize("mode", ["clamp", "mirror"])
def test_wrapped_texture_matches_mitsuba(tmp_path, mode):
    write_texture(tmp_path / "t.png")
    quad_gltf(tmp_path / "q.gltf", (mode, mode))
    (tmp_path / "s.toml").write_text('[camera]\neye = [0.0, 0.0, 4.0]\ncenter = [0.0, 0.0, 0.0]\nfovy = 60.0\n'
                                     'width = 96\nheight = 96\n[render]\nambient = [0.2, 0.2, 0.2]\n'
                                     '[[lights]]\nposition = [1.0, 2.0, 5.0]\ncolor = [0.8, 0.8, 0.8]\n'
                                     '[[objects]]\nmesh = "q.gltf"\n')
    check(f"texture_wrap_{mode}", warprt.load_scene(tmp_path / "s.toml"))
