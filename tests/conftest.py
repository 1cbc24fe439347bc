"""Shared test set-up: Mitsuba's LLVM, and the suites whose every test runs on both primary paths."""

import os
from pathlib import Path

os.environ.setdefault("DRJIT_LIBLLVM_PATH", "/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1")

import pytest

# The hybrid promises the traced image to the bit, so each closed form, count and stability property
# of these suites must hold with every first hit traced and with the hybrid's (the Z-buffer's where
# certain, traced elsewhere): each of their tests runs once on each path.
BOTH_PRIMARIES = ("core", "effects", "stability")
PRIMARIES = ("raytrace", "zbuffer")


def pytest_generate_tests(metafunc):
    if Path(str(metafunc.definition.fspath)).parent.name in BOTH_PRIMARIES:
        metafunc.fixturenames.append("primary_path")
        metafunc.parametrize("primary_path", PRIMARIES, indirect=True)


@pytest.fixture
def primary_path(request, monkeypatch):
    """render()'s default first-hit path for this test (warprt.image.DEFAULTS.primary)."""
    import warprt.image

    monkeypatch.setattr(warprt.image.DEFAULTS, "primary", request.param)
    return request.param
