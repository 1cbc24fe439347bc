"""Shared test set-up: Mitsuba's LLVM, and the suites whose every test runs on every render path."""

import os
import sys
from pathlib import Path

os.environ.setdefault("DRJIT_LIBLLVM_PATH", "/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1")

import pytest

# Every shortcut promises the traced image to the bit, so each closed form, count and stability
# property of these suites must hold with every ray traced from a BVH built at the eye, and with every
# shortcut at once: the first hits from the Z-buffer where certain, shadow rays from the light-space
# grid, reflections off planar mirrors from their virtual cameras, on a BVH whose frame origin is moved
# half the scene's reach away (shifted_geometries), so camera rays start far from zero. Two paths keep the suite's time what it was; each
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
    """render()'s defaults for this test's path (warprt.image.DEFAULTS), and the Geometries it builds."""
    import warprt.image

    path = dict(PATHS[request.param])
    shift = path.pop("origin_shift")
    for name, value in path.items():
        monkeypatch.setattr(warprt.image.DEFAULTS, name, value)
    if shift:
        shifted_geometries(monkeypatch, shift)
    return request.param


def shifted_geometries(monkeypatch, shift: float):
    """The Geometries render() builds for its frames (renderer.frame_geometry) get a frame origin moved
    ``shift`` R along a fixed slant (R: the largest coordinate of the scene relative to the origin the
    rule gives), where the eye stays in the region their BVH covers; kept in a cache of their own."""
    import numpy as np

    import warprt.image
    from warprt.geometry import Geometry, frame_origin, objects_center
    from warprt.scene import ObjectCache

    renderer = sys.modules[warprt.image.render.__module__]
    slant = np.array([1.0, -0.75, 0.5])  # not along an axis: every coordinate moves

    def shifted(scene, device="cpu", **kw):
        if kw or not scene.objects:
            return Geometry(scene, device=device, **kw)
        origin = frame_origin(*objects_center(scene.objects), scene.camera.eye)
        reach = max(float(np.abs(o.vertices - origin).max(initial=0.0)) for o in scene.objects)
        geom = Geometry(scene, device=device, origin=origin + shift * reach * slant)
        return geom if geom.covers(scene.camera.eye) else Geometry(scene, device=device)

    monkeypatch.setattr(renderer, "Geometry", shifted)
    monkeypatch.setattr(renderer, "geometry_cache", ObjectCache(size=4))
