"""Shared test set-up: Mitsuba's LLVM, and the suites whose every test runs on every render path."""

import os
from pathlib import Path

os.environ.setdefault("DRJIT_LIBLLVM_PATH", "/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1")

import pytest

# Every shortcut promises the traced image to the bit, so each closed form, count and stability
# property of these suites must hold with every ray traced from a BVH built at the eye, and with every
# shortcut at once: the first hits from the Z-buffer where certain, shadow rays from the light-space
# grid, reflections off planar mirrors from their virtual cameras, on a BVH whose frame origin is moved
# half the scene's reach away (warprt.image.DEFAULTS.origin_shift), so camera rays start far from zero. Two paths keep the suite's time what it was; each
# shortcut is also held to the traced image on its own, on every scene, hard case and random scene
# (tests/zbuffer, tests/shadows, tests/mirrors, tests/geometry).
PATH_SUITES = ("core", "effects", "stability")
PATHS = {
    "traced": {"primary": "raytrace", "shadows": "bvh", "reflections": "bvh", "origin_shift": 0.0},
    "shortcuts": {"primary": "zbuffer", "shadows": "grid", "reflections": "mirrors", "origin_shift": 0.5},
}


def pytest_generate_tests(metafunc):
    if Path(str(metafunc.definition.fspath)).parent.name in PATH_SUITES:
        metafunc.fixturenames.append("render_path")
        metafunc.parametrize("render_path", list(PATHS), indirect=True)


@pytest.fixture
def render_path(request, monkeypatch):
    """render()'s defaults for this test's path (warprt.image.DEFAULTS)."""
    import warprt.image

    for name, value in PATHS[request.param].items():
        monkeypatch.setattr(warprt.image.DEFAULTS, name, value)
    return request.param
