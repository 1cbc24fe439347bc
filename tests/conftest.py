"""Shared test set-up: scenes are built from dicts shaped like the TOML file."""

import os

os.environ.setdefault("DRJIT_LIBLLVM_PATH", "/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1")


import pytest


@pytest.fixture(params=["raytrace", "zbuffer"])
def both_primaries(request, monkeypatch):
    """Run a test once with every first hit traced and once with the hybrid's (the Z-buffer's where
    certain, traced elsewhere), by changing warprt.render's default: each closed form, count and
    stability property must hold for both, since the hybrid promises the traced image to the bit."""
    from warprt import renderer

    monkeypatch.setitem(renderer.render.__kwdefaults__, "primary", request.param)
    return request.param
