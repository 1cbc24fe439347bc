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
# half the scene's reach away (shifted_geometry), so camera rays start far from zero. Two paths keep the suite's time what it was; each
# shortcut is also held to the traced image on its own, on every scene, hard case and random scene
# (tests/zbuffer, tests/shadows, tests/mirrors, tests/geometry).
PATH_SUITES = ("core", "effects", "stability")
PATHS = {
    "traced": {"primary_query": "raytrace", "shadow_query": "bvh", "reflection_query": "bvh", "origin_shift": 0.0},
    "shortcuts": {"primary_query": "zbuffer", "shadow_query": "grid", "reflection_query": "mirrors", "origin_shift": 0.5},
}


def pytest_generate_tests(metafunc):
    if Path(str(metafunc.definition.fspath)).parent.name in PATH_SUITES:
        metafunc.fixturenames.append("render_path")
        metafunc.parametrize("render_path", list(PATHS), indirect=True)


@pytest.fixture
def render_path(request, monkeypatch):
    """warprt.render for this test's path: the path's queries wherever the test names none, and with an
    origin shift, a Geometry built with that frame origin (shifted_geometry) handed over as render's
    ``geometry``. Only the public options change; the test's own options win."""
    import warprt

    path = dict(PATHS[request.param])
    shift = path.pop("origin_shift")
    plain = warprt.render

    def path_render(scene, options=None, **kw):
        if options is None:
            kw = {**path, **kw}
        if shift and kw.get("geometry") is None:
            algorithm = kw.get("algorithm", getattr(options, "algorithm", "raytrace"))
            if algorithm == "raytrace":
                kw["geometry"] = shifted_geometry(scene, shift)
        return plain(scene, options, **kw)

    monkeypatch.setattr(warprt, "render", path_render)
    return request.param


def shifted_geometry(scene, shift: float):
    """A Geometry for ``scene`` whose frame origin is moved ``shift`` R along a fixed slant (R: the largest
    coordinate of the scene relative to the origin the rule gives), where the eye stays in the region
    its BVH covers; None (render builds its own) where it would not, or the scene has no objects."""
    import numpy as np

    from warprt.geometry import Geometry, frame_origin, objects_center

    if not scene.objects:
        return None
    slant = np.array([1.0, -0.75, 0.5])  # not along an axis: every coordinate moves
    origin = frame_origin(*objects_center(scene.objects), scene.camera.eye)
    reach = max(float(np.abs(o.vertices - origin).max(initial=0.0)) for o in scene.objects)
    geom = Geometry(scene, origin=origin + shift * reach * slant)
    return geom if geom.covers(scene.camera.eye) else None
