"""The gradient's record is the forward's own trace (issue 37): Renderer.render(grad=True) writes what
backward() holds fixed as its trace kernel finds it, so a grad frame traces no ray twice, its image is the
plain frame's to the bit, and the record does not depend on which exact query answered a ray.

Independent checks: the plain frame's image (another kernel variant, without the record's code), the record
made with every ray traced by the BVH against the one made with the Z-buffer's first hits, the shadow grid
and the mirrors' virtual cameras (each exact: the same answers), the Z-buffer's own visible faces, and the
generated C++ of the plain variant (the record's code absent from it).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import warprt
import warprt.image
from warprt.kernels import NO_RAY, init_warp, make_trace_kernel, wp
from warprt.scene import EffectSet

WIDTH, HEIGHT = 40, 30


def scene(light_colour=1.0, floor_kr=0.3):
    """A mirror floor, a smooth ball and a box, two point lights with shadows: camera rays, shadow rays and
    mirror rays over three levels, each shortcut's case (a planar mirror, grid shadows, Z-buffer hits)."""
    return warprt.load_dict({
        "camera": {"eye": [0.0, 2.0, 5.0], "center": [0.0, 0.5, 0.0], "width": WIDTH, "height": HEIGHT},
        "render": {"ambient": [0.1] * 3, "max_depth": 3},
        "lights": [{"position": [2.0, 4.0, 3.0], "color": [0.8 * light_colour] * 3},
                   {"position": [-3.0, 2.5, 1.0], "color": [0.4 * light_colour] * 3}],
        "materials": {"floor": {"kd": [0.4, 0.35, 0.3], "ks": [0.2] * 3, "shininess": 16.0,
                                "reflectivity": floor_kr},
                      "ball": {"kd": [0.6, 0.2, 0.1], "ks": [0.5] * 3, "shininess": 40.0}},
        "objects": [{"shape": "plane", "size": [8.0, 8.0], "material": "floor"},
                    {"shape": "sphere", "subdivisions": 3, "smooth": True, "translate": [0.0, 0.8, 0.0],
                     "scale": 0.8, "material": "ball"},
                    {"shape": "box", "size": [0.6, 0.6, 0.6], "translate": [1.3, 0.3, 0.5], "material": "ball"}]})


TRACED = dict(primary_query="raytrace", shadow_query="bvh", reflection_query="bvh")
SHORTCUTS = dict(primary_query="zbuffer", shadow_query="grid", reflection_query="mirrors")


def record(s, **options):
    r = warprt.Renderer(s, threads=1, **options)
    result = r.render(grad=True)
    return result, r._first_hits[2]


@pytest.fixture(scope="module")
def traced():
    return record(scene(), **TRACED)


def arrays(hits) -> dict:
    return {k: getattr(hits.rec, k).numpy() for k in ("face", "bary", "visible")}


def chain(hits, key: str = "face") -> np.ndarray:
    """A chain's record of ``key`` per camera ray and level, (camera rays, levels, ...): entry k n + ray."""
    a = getattr(hits.rec, key).numpy()[:hits.entries]
    return np.moveaxis(a.reshape((hits.levels, hits.camera_rays) + a.shape[1:]), 0, 1)


def test_a_grad_frame_is_the_plain_frame_to_the_bit(traced):
    result, _ = traced
    plain = warprt.Renderer(scene(), threads=1, **TRACED).render()
    assert np.array_equal(result.image, plain.image)
    assert result.stats.rays == plain.stats.rays  # no ray traced twice: the record is the trace's own
    assert "grad_record" not in result.stats.times


def test_the_record_holds_the_frames_levels(traced):
    _, hits = traced
    face = chain(hits)
    assert hits.levels == 3 and face.shape[0] == WIDTH * HEIGHT
    assert (face[:, 0] != NO_RAY).all()  # every camera ray is recorded
    # a chain reaches level j + 1 only from a hit at level j (the floor mirrors, the ball does not)
    assert ((face[:, 1:] == NO_RAY) | (face[:, :-1] >= 0)).all()
    assert (face[:, 1] >= 0).any() and (face[:, 1] == NO_RAY).any()
    # the barycentrics of each hit lie in its triangle (Warp's: u on the first vertex, v on the second)
    bary = chain(hits, "bary")[face >= 0]
    assert (bary >= -1e-6).all() and (bary.sum(1) <= 1.0 + 1e-6).all()


def test_the_record_is_the_same_whichever_exact_query_answers(traced):
    """The Z-buffer's first hits, the light-space grid's shadow answers and the mirrors' virtual cameras
    give the BVH's answers to the bit, so the record they write is the traced one's; the same image too."""
    result, hits = traced
    short_result, short = record(scene(), **SHORTCUTS)
    assert short_result.stats.shadow_query == "grid" and short_result.stats.primary_query == "zbuffer"
    assert np.array_equal(short_result.image, result.image)
    for key, a in arrays(hits).items():
        b = arrays(short)[key]
        taken = hits.rec.face.numpy() >= 0
        assert np.array_equal(a[taken], b[taken]), key


def test_the_camera_rays_faces_are_the_zbuffers_visible_faces(traced):
    """Independent of the tracer: the rasterizer's visible triangle per pixel (render_zbuffer's faces)."""
    _, hits = traced
    _, faces = warprt.image.render_zbuffer(scene(), threads=1, return_faces=True)
    first = chain(hits)[:, 0].reshape(HEIGHT, WIDTH)
    agree = first == faces[..., 0]
    assert agree.mean() > 0.97  # silhouette pixels may differ (the rasterizer's own coverage rule)


def test_values_that_switch_an_effect_off_are_recorded_and_add_nothing():
    """A light of colour 0 (no shadow rays in the plain frame), kd and ks of 0 everywhere (no light loop) and
    a named reflectivity of 0 (no mirror rays): the grad frame traces what the record needs, and its image
    is still the plain frame's to the bit."""
    dark = scene(light_colour=0.0)
    r = warprt.Renderer(dark, threads=1, **TRACED)
    result = r.render(grad=True)
    hits = r._first_hits[2]
    assert np.array_equal(result.image, warprt.Renderer(dark, threads=1, **TRACED).render().image)
    seen = hits.rec.visible.numpy()[:hits.entries][hits.rec.face.numpy()[:hits.entries] >= 0]  # a bit a light
    assert (seen & 1).any() and not (seen & 1).all()  # shadow rays traced: some hits see a light, some do not
    assert result.stats.rays["shadow"] > 0

    s = scene(floor_kr=0.0)
    r = warprt.Renderer(s, threads=1, **TRACED)
    result = r.render(grad=["materials.floor.reflectivity"])
    face = chain(r._first_hits[2])
    assert (face[:, 1] >= -1).any()  # the floor's mirror rays, followed with weight 0
    assert np.array_equal(result.image, warprt.Renderer(s, threads=1, **TRACED).render().image)


def _generated_source(**kwargs) -> str:
    init_warp()
    kernel = make_trace_kernel(EffectSet(reflection=True, area_lights=True), **kwargs)
    wp.load_module(kernel.module, device="cpu")
    (module_exec,) = kernel.module.execs.values()
    return Path(module_exec.binary_path).with_suffix("").with_suffix(".cpp").read_text()


def test_the_record_is_absent_from_the_plain_kernel():
    """The lines that write the record, as Warp quotes them in the C++ it compiles."""
    markers = ("j = record_hit(rec, ", "seen = seen | (t.lit << l)", "rec.emit[j] = emitter_met(",
               "rec.area_bits[word] = rec.area_bits[word] | (1 << (q % 32))")
    assert not any(m in _generated_source() for m in markers)
    assert all(m in _generated_source(record=True) for m in markers)


def glass(transmittance=0.9, max_depth=5):
    """A glass ball on a mirror floor under a point light: a ray tree (both children at the ball, total internal
    reflection inside it, mirror rays off the floor) over ``max_depth`` levels."""
    return warprt.load_dict({
        "camera": {"eye": [0.0, 1.5, 4.0], "center": [0.0, 0.7, 0.0], "width": WIDTH, "height": HEIGHT},
        "render": {"ambient": [0.1] * 3, "max_depth": max_depth},
        "lights": [{"position": [2.0, 4.0, 3.0], "color": [0.8] * 3}],
        "materials": {"floor": {"kd": [0.4, 0.35, 0.3], "reflectivity": 0.3},
                      "glass": {"kd": [0.0] * 3, "ks": [0.3] * 3, "shininess": 60.0, "ior": 1.5,
                                "transmittance": [transmittance] * 3}},
        "objects": [{"shape": "plane", "size": [8.0, 8.0], "material": "floor"},
                    {"shape": "sphere", "subdivisions": 3, "smooth": True, "translate": [0.0, 0.8, 0.0],
                     "scale": 0.8, "material": "glass"}]})


def entries(hits) -> dict:
    """The record's entries that rays reached, per level: {level: (face, parent, camera ray, medium)}."""
    out, face = {}, hits.rec.face.numpy()
    for k in range(hits.levels):
        first, count = hits.level(k)
        take = np.flatnonzero(face[first:first + count] != NO_RAY) + first
        out[k] = tuple(getattr(hits.rec, key).numpy()[take] for key in ("face", "parent", "ray_of", "medium"))
    return out


def test_glass_is_recorded_by_its_trace():
    """Glass's ray tree is the trace's own too: the grad frame's image and ray counts are the plain frame's, and
    its deeper levels hold exactly the reflected and refracted rays the plain frame counted (its own kernel's
    counters), each the child of a hit of the level before on the same camera ray, at most one a branch."""
    s = glass()
    r = warprt.Renderer(s, threads=2)
    result = r.render(grad=True)
    plain = warprt.Renderer(s, threads=2).render()
    assert np.array_equal(result.image, plain.image) and result.stats.rays == plain.stats.rays
    hits = r._first_hits[2]
    assert hits.tree and not hits.overflowed()
    levels = entries(hits)
    deeper = sum(len(levels[k][0]) for k in range(1, hits.levels))
    assert deeper == plain.stats.rays["reflection"] + plain.stats.rays["refraction"]
    face = hits.rec.face.numpy()
    for k in range(1, hits.levels):
        f, parent, ray_of, _ = levels[k]
        mother = parent // 2
        first, count = hits.level(k - 1)
        assert ((mother >= first) & (mother < first + count)).all()  # a ray of the level before
        assert (face[mother] >= 0).all() and (hits.rec.ray_of.numpy()[mother] == ray_of).all()
        assert len(np.unique(parent)) == len(parent)  # one child a branch
    both = np.unique(levels[1][1] // 2, return_counts=True)[1]
    assert (both == 2).any()  # a tree, not a chain: rays with both children


def test_a_region_too_small_is_grown_and_traced_again():
    """A first frame whose glass regions are too small (one entry a band and level) is traced again with larger
    ones: the same record, entry for entry by camera ray and parent's path, as a frame with room to spare."""
    s = glass()
    small = warprt.Renderer(s, threads=2)
    small._record_used = np.zeros((16, 5), np.int64)  # room for 16 rays a band and level: far too few
    small.render(grad=True)
    roomy = warprt.Renderer(s, threads=2)
    roomy.render(grad=True)
    a, b = small._first_hits[2], roomy._first_hits[2]
    assert not a.overflowed() and (a.capacity[:, 1:] > 16).any()
    for k, (x, y) in enumerate(zip(entries(a).values(), entries(b).values())):
        key = lambda e: np.lexsort((e[0], e[2]))  # noqa: E731 (the order within a level is the trace's)
        assert all(np.array_equal(u[key(x)], v[key(y)]) for u, v in ((x[0], y[0]), (x[2], y[2]), (x[3], y[3]))), k


def test_a_transmittance_of_0_has_its_refracted_rays_recorded_with_weight_0():
    """The forward leaves out a refracted ray that carries nothing; the record follows it (its radiance is that
    transmittance's derivative), the image the plain frame's to the bit."""
    s = glass(transmittance=0.0)
    r = warprt.Renderer(s, threads=2)
    result = r.render(grad=True)
    plain = warprt.Renderer(s, threads=2).render()
    assert np.array_equal(result.image, plain.image) and plain.stats.rays["refraction"] == 0
    hits = r._first_hits[2]
    assert (entries(hits)[1][1] % 2 == 1).any()  # transmitted children at level 1
