"""A warm frame of an unchanged scene stays on its device: what crosses between host and device is the image,
the ray counts and a few bytes of totals, whatever path the frame takes (issue 31). Counted on the CPU at the
two doors every transfer goes through, wp.array(data) (an upload) and wp.array.numpy() (a download): on a GPU
the same calls are the copies, so the count is the one a GPU run would show."""

import contextlib
import traceback

import numpy as np
import pytest
import warp as wp

import warprt
from marks import slow
from warprt.scene import resolve_effects

SCENES = {"default": None, "glass_cube": "scenes/glass_cube.toml", "textured": "scenes/textured.toml",
          "whitted": "scenes/whitted.toml"}


@contextlib.contextmanager
def transfers():
    """Every upload and download inside the block: (direction, bytes, where in warprt)."""
    log = []
    numpy, init = wp.array.numpy, wp.array.__init__

    def where():
        frames = [f for f in traceback.extract_stack()[:-2] if "/warprt/" in f.filename]
        return f"{frames[-1].filename.rsplit('/warprt/', 1)[1]}:{frames[-1].lineno}" if frames else "?"

    def counted_numpy(self):
        log.append(("down", self.capacity, where()))
        return numpy(self)

    def counted_init(self, data=None, *args, **kwargs):
        if data is not None and not isinstance(data, wp.array):
            log.append(("up", int(np.asarray(data).nbytes), where()))
        return init(self, data, *args, **kwargs)

    wp.array.numpy, wp.array.__init__ = counted_numpy, counted_init
    try:
        yield log
    finally:
        wp.array.numpy, wp.array.__init__ = numpy, init


def warm_renderer(name, **options):
    path = SCENES[name]
    scene = warprt.load_scene(path, {"camera.width": 160, "camera.height": 120})
    r = warprt.Renderer(scene, **options)
    for _ in range(3):  # the third frame of a view keeps the auto policies' grids and rasters
        r.render()
    return r


PATHS = [("default", {}),  # auto: the Z-buffer's first hits, the kept shadow grid and mirror rasters
         ("default", dict(primary_query="raytrace", shadow_query="bvh", reflection_query="bvh")),
         ("glass_cube", dict(primary_query="zbuffer")), ("textured", {}), ("whitted", {}),
         ("default", dict(algorithm="zbuffer"))]


@slow  # six scenes, four frames each at 160x120
@pytest.mark.parametrize("name, options", PATHS, ids=[f"{n}-{o or 'auto'}" for n, o in PATHS])
def test_a_warm_frame_moves_only_its_image_counts_and_totals(name, options):
    r = warm_renderer(name, **options)
    with transfers() as log:
        result = r.render()
    n = 160 * 120
    assert [t for t in log if t[0] == "up"] == [], log  # the scene's tables stay on the device
    down = sorted(t[1] for t in log if t[0] == "down")
    per_pixel = 16 if resolve_effects(r.scene).refraction else 12  # vec4i counts with refraction rays, else vec3i
    expected = [n * 12] if options.get("algorithm") == "zbuffer" else sorted([n * 12, n * per_pixel])
    assert [b for b in down if b > 8] == expected, log
    # The rest are totals: the Z-buffer's pair count (4 bytes) where it rasterized, the mirrors' decided
    # count (8) where their rasters answered.
    rasterized = result.stats.primary_query == "zbuffer" or options.get("algorithm") == "zbuffer"
    totals = sorted(([4] if rasterized else []) + ([8] if result.stats.reflection_query == "mirrors" else []))
    assert [b for b in down if b <= 8] == totals, log


def test_a_changed_parameter_is_uploaded_and_only_then():
    """The negative control: the counter sees uploads, and they come when a parameter changes."""
    r = warm_renderer("default", primary_query="raytrace", shadow_query="bvh", reflection_query="bvh")
    name = r.scene.objects[0].material
    before = r.render().image
    r.params[f"materials.{name}.kd"] = [0.25, 0.5, 0.75]
    with transfers() as log:
        changed = r.render().image
    assert any(t[0] == "up" for t in log) and not np.array_equal(changed, before)
    with transfers() as log:
        r.render()
    assert not any(t[0] == "up" for t in log)
