"""Gradients under area lights (issue 30 over issue 32's lights): lights.<i>.radiance, an emitting material's
materials.<name>.emission, and the materials, a texture and a flat object's vertices under them. The record
keeps per ray level the emitter whose front the ray meets and a bit per sample point the hit sees; the replay
adds each seen sample's term (kernels.replay_area, one thread per entry and sample, wp.atomic_add) and the
emitted radiance (the forward's area_arrival and area_term). The sample points are held fixed, as visibility is. Checked:

- the replayed image is the forward's, to the bit, at 16 and 64 samples, with an emitting material, and in
  Mitsuba's Cornell box (scenes/cornell_box.xml at 24 x 24);
- per component central finite differences of the forward (no mask: none of these parameters moves an edge;
  the image is linear in all but shininess, so h = 1e-2 of the value's scale), and along random directions
  for a texture's texels and the floor's vertices (edges masked, tests/grad/directional.py);
- warp.autograd.gradcheck of the sample term (shading.point_arrival, area_term);
- controls that fail: visibility ignored (shadows off), the emitter's cosine dropped, each sample weighted
  as the first sample point, the emitter seen directly left out, the gradient read along another direction.

Measured (CPU): replay - forward exactly 0 in each scene; relative errors 2e-7 to 1.2e-5 for colours,
radiance and emission, 1e-5 to 2e-4 for shininess, 3e-6 for the texture, 4e-4 for the vertices.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
import warp as wp
import warp.autograd

import warprt
from warprt.geometry import SceneData
from warprt.kernels import (Coefficients, GradRecord, ReplayHits, Surface, area_arrival, make_light_terms,
                            point_arrival)
from warprt.scene import Texture, resolve_effects

from .directional import backward_masked, directional, random_direction

AREA_TERM = make_light_terms(True, True)[1]  # what one area-light sample point the hit sees adds

WIDTH, HEIGHT = 24, 18
REL = 1e-3
CORNELL = Path(__file__).resolve().parents[2] / "scenes" / "cornell_box.xml"
TEXELS = np.random.default_rng(2).uniform(0.2, 1.0, (5, 6, 3)).astype(np.float32)


def soft(samples: int = 16):
    """A glossy sphere over a glossy, weakly mirroring floor (two levels) under a tilted rectangle light,
    the sphere's soft shadow in view and the light's front seen directly."""
    return warprt.load_dict({
        "camera": {"eye": [0.0, 1.6, 5.0], "center": [0.0, 1.0, 0.0], "width": WIDTH, "height": HEIGHT},
        "render": {"ambient": [0.05] * 3, "max_depth": 2, "light_samples": samples},
        "lights": [{"type": "area", "shape": "rectangle", "center": [0.4, 2.6, 0.3], "normal": [0.0, -1.0, 0.5],
                    "size": [1.2, 0.8], "radiance": [6.0, 5.0, 4.0]}],
        "materials": {"floor": {"kd": [0.4, 0.35, 0.3], "ks": [0.2] * 3, "shininess": 16.0, "reflectivity": [0.3] * 3},
                      "ball": {"kd": [0.6, 0.2, 0.1], "ks": [0.5] * 3, "shininess": 40.0}},
        "objects": [{"shape": "plane", "size": [8.0, 8.0], "material": "floor"},
                    {"shape": "sphere", "subdivisions": 2, "smooth": True, "translate": [0.0, 0.8, 0.0], "scale": 0.8,
                     "material": "ball"}]})


def lamp(texture: bool = False):
    """A tilted emissive square (material emission: an object light, its front in view) over a flat floor,
    a sphere casting its soft shadow, one level; with ``texture``, the floor's kd textured."""
    s = warprt.load_dict({
        "camera": {"eye": [0.0, 1.2, 5.0], "center": [0.0, 1.2, 0.0], "width": WIDTH, "height": HEIGHT},
        "render": {"ambient": [0.05] * 3, "max_depth": 1, "light_samples": 16},
        "materials": {"floor": {"kd": [0.4, 0.35, 0.3], "ks": [0.2] * 3, "shininess": 16.0},
                      "lamp": {"kd": [0.1, 0.1, 0.1], "emission": [4.0, 3.5, 3.0]},
                      "ball": {"kd": [0.6, 0.2, 0.1], "ks": [0.5] * 3, "shininess": 40.0}},
        "objects": [{"name": "floor", "shape": "plane", "size": [8.0, 8.0], "material": "floor"},
                    {"name": "lamp", "shape": "plane", "size": [1.0, 1.0], "rotate": [150.0, 0.0, 0.0],
                     "translate": [0.3, 2.4, 0.2], "material": "lamp"},
                    {"name": "ball", "shape": "sphere", "subdivisions": 2, "smooth": True, "translate": [0.0, 0.6, 0.0],
                     "scale": 0.6, "material": "ball"}]})
    if not texture:
        return s
    mats = dict(s.materials)
    mats["floor"] = replace(mats["floor"], kd_texture=Texture(image=TEXELS, uv_transform=(3.0, 0.0, 0.25, 0.0, 3.0, -0.1)))
    return replace(s, materials=mats)


def cornell(samples: int = 16):
    """Mitsuba's Cornell box from its XML (an object light under the ceiling), 24 x 24."""
    return warprt.load_scene(CORNELL).with_camera(width=24, height=24).with_render(light_samples=samples)


SCENES = {"soft": soft, "soft64": lambda: soft(64), "lamp": lamp, "cornell": cornell}


def weights_for(s) -> np.ndarray:
    return np.random.default_rng(5).random((s.camera.height, s.camera.width, 3)).astype(np.float32)


def component_differences(s, name: str, weights, rel: float) -> np.ndarray:
    """Central differences of sum(weights * image) in each component of ``name``, set through r.params, at
    h = rel * max(|value|, 1)."""
    r = warprt.Renderer(s)
    base = np.asarray(r.params[name], np.float64)
    h = rel * max(float(np.abs(base).max()), 1.0)

    def loss(value) -> float:
        r.params[name] = value
        return float((weights.astype(np.float64) * r.render().image).sum())

    steps = np.eye(base.size).reshape(-1, *base.shape) if base.ndim else [1.0]
    out = np.asarray([(loss(base + h * e) - loss(base - h * e)) / (2 * h) for e in steps])
    r.close()
    return out.reshape(base.shape)


def gradients(s, weights, names, **options) -> dict:
    r = warprt.Renderer(s, **options)
    r.render(grad=True)
    out = r.backward(weights, wrt=names, edges=False)
    r.close()
    return out


def relative(g, fd) -> float:
    return float(np.abs(np.asarray(g) - fd).max() / np.abs(fd).max())


@pytest.mark.parametrize("key", SCENES)
def test_the_replayed_image_is_the_forward_image(key):
    s = SCENES[key]()
    r = warprt.Renderer(s)
    forward = r.render().image
    geom = r.geometry
    hits = warprt.image.record_first_hits(s, geom, geom.scene_data(s), resolve_effects(s), "cpu")
    assert hits.words > 0 and np.asarray(hits.rec.area_bits.numpy()).any()
    assert np.array_equal(warprt.image.replay_image(s, geom, hits, "cpu"), forward)


CHECKS = [("soft", "lights.0.radiance"), ("soft", "materials.floor.kd"), ("soft", "materials.floor.ks"),
          ("soft", "materials.ball.kd"), ("soft", "materials.ball.shininess"), ("soft", "materials.floor.reflectivity"),
          ("soft64", "lights.0.radiance"), ("soft64", "materials.ball.shininess"),
          ("lamp", "materials.lamp.emission"), ("lamp", "materials.floor.kd"), ("lamp", "materials.ball.ks"),
          ("cornell", "lights.0.radiance"), ("cornell", "materials.white.kd"), ("cornell", "materials.red.kd")]


@pytest.mark.parametrize("key, name", CHECKS)
def test_gradients_equal_central_differences(key, name):
    s = SCENES[key]()
    w = weights_for(s)
    g = gradients(s, w, [name])[name]
    fd = component_differences(s, name, w, 1e-3 if name.endswith("shininess") else 1e-2)
    assert g.shape == fd.shape and np.abs(fd).max() > 0
    assert relative(g, fd) <= REL, (g, fd)


def test_texture_and_vertex_gradients_equal_central_differences():
    """Along random directions: the floor's kd texels (the image linear in them) and, untextured, the flat
    floor's vertices (the hits slide, the sample points stay), edges masked; each read along another
    direction as the control."""
    for s, name, rel, h in ((lamp(texture=True), "materials.floor.kd_texture", 1.0, 1e-2),
                            (lamp(), "objects.floor.vertices", 0.05, 1e-3)):
        w = weights_for(s)
        d = directional(s, random_direction(s, [name], rel=rel), w, h=h)
        assert d.masked < 0.05
        g = backward_masked(s, w, d)
        assert d.error(g) <= 2e-3, (name, d.gradient(g), d.fd)
        other = random_direction(s, [name], seed=4, rel=rel)[name]
        assert abs((g[name] * other).sum() - d.fd) > 0.1 * abs(d.fd), name


def test_visibility_ignored_does_not():
    """The control: the replay with every sample seen (shadows off, so the record finds no blocker) against
    the differences of the shadowed image."""
    s = soft()
    w = weights_for(s)
    names = ["lights.0.radiance", "materials.floor.kd"]
    wrong = gradients(s, w, names, disable=["shadows"])
    for name in names:
        assert relative(wrong[name], component_differences(s, name, w, 1e-2)) > 20 * REL, name


@pytest.mark.parametrize("dark, name", [({"lights.0.radiance": [0.0] * 3}, "lights.0.radiance"),
                                        ({"lights.0.color": [0.0] * 3, "lights.1.color": [0.0] * 3}, "lights.0.color")])
def test_a_dark_light_has_the_shadowed_gradient(dark, name):
    """With every light dark the forward traces no shadow ray (its image is the same without), but the
    derivative there is the shadowed image's: the record traces them. An area light, and two point lights
    (test_first_hit_gradients' scene). The image is linear in the light, so a one-sided difference from 0
    is exact to float32. (Before, the shadows were left out: 0.045 off for the area light.)"""
    from .test_first_hit_gradients import scene as point_lit

    s = soft() if name.endswith("radiance") else point_lit()
    w = weights_for(s)
    r = warprt.Renderer(s)
    r.params.update(dark)
    r.render(grad=True)
    g = r.backward(w, wrt=[name], edges=False)[name]

    def loss(value) -> float:
        r.params[name] = value
        return float((w.astype(np.float64) * r.render().image).sum())

    zero = loss([0.0, 0.0, 0.0])
    fd = np.asarray([loss(list(e)) - zero for e in np.eye(3)])
    r.close()
    assert relative(g, fd) <= REL, (g, fd)


def test_a_dark_light_with_shadows_switched_off_has_the_unshadowed_gradient():
    """The other side of the test above: shadows switched off by the caller (disable=) stay off in the
    record of a dark scene, where the scene's values alone would not have them traced: the gradient at
    radiance 0 is the unshadowed image's (a one-sided difference from 0 with shadows off), not the
    shadowed one's (the control, measured 0.045 apart)."""
    s = soft()
    w = weights_for(s)
    name = next(n for n in warprt.Renderer(s).params if n.endswith("radiance"))

    def gradient_and_fd(**options):
        r = warprt.Renderer(s, **options)
        r.params[name] = [0.0, 0.0, 0.0]
        r.render(grad=True)
        g = r.backward(w, wrt=[name], edges=False)[name]

        def loss(value) -> float:
            r.params[name] = value
            return float((w.astype(np.float64) * r.render().image).sum())

        fd = np.asarray([loss(list(e)) for e in np.eye(3)]) - loss([0.0, 0.0, 0.0])
        r.close()
        return g, fd

    g_off, fd_off = gradient_and_fd(disable=["shadows"])
    _, fd_on = gradient_and_fd()
    assert relative(g_off, fd_off) <= REL, (g_off, fd_off)
    assert relative(g_off, fd_on) > 10 * REL


# --- Controls by a changed replay: the same record and launches with one kernel swapped ----------------------

@wp.kernel
def _no_cosine(s: SceneData, rec: GradRecord, live: wp.array(dtype=int), sample_light: wp.array(dtype=int),
               hits: ReplayHits):
    """replay_area with the emitter's cosine dropped: the sample's normal taken along the light's direction."""
    t, q = wp.tid()
    j = live[t]
    if rec.face[j] >= 0:
        if (rec.area_bits[j * rec.words + q / 32] >> (q % 32)) & 1 != 0:
            hit = hits.hit[j]
            a = area_arrival(s, hit, q)
            a.cos_q = 1.0
            wp.atomic_add(hits.local, j, AREA_TERM(a, s.area.radiance[sample_light[q]], s.area.dA[q], hits.k[j],
                                                   s.shininess[hit.material], hit.n, -hits.direction[j]))


@wp.kernel
def _first_sample(s: SceneData, rec: GradRecord, live: wp.array(dtype=int), sample_light: wp.array(dtype=int),
                  hits: ReplayHits):
    """replay_area with each seen sample weighted as the light's first sample point would be (the wrong
    sample's weight: a shifted or permuted index is no control, each hit seeing nearly the same sum)."""
    t, q = wp.tid()
    j = live[t]
    if rec.face[j] >= 0:
        if (rec.area_bits[j * rec.words + q / 32] >> (q % 32)) & 1 != 0:
            hit = hits.hit[j]
            wp.atomic_add(hits.local, j, AREA_TERM(area_arrival(s, hit, 0), s.area.radiance[sample_light[q]],
                                                   s.area.dA[0], hits.k[j], s.shininess[hit.material], hit.n,
                                                   -hits.direction[j]))


def replayed_gradient(s, weights, name: str, area_kernel=None, no_emission: bool = False) -> np.ndarray:
    """d(sum(weights * image)) / d(param) for ``name``, ``s``'s only area light's radiance or a material's kd,
    by the public replay (warprt.image.build_replay) launched on a wp.Tape, with ``area_kernel`` in place of
    kernels.replay_area and, with ``no_emission``, the emitter seen directly left out (the record's emit all -1)."""
    r = warprt.Renderer(s)
    r.render()
    geom = r.geometry
    hits = warprt.image.record_first_hits(s, geom, geom.scene_data(s), resolve_effects(s), "cpu")
    if no_emission:
        hits.rec.emit.fill_(-1)
    replay = warprt.image.build_replay(s, geom, hits, "cpu")
    if area_kernel is not None:
        replay.area_kernel = area_kernel
    tape = wp.Tape()
    with tape:
        replay.launch()
    tape.backward(grads={replay.colour: wp.array(weights.reshape(-1, 3), dtype=wp.vec3)})
    _, owner, key = name.split(".")
    row = geom.material_names.index(owner) if key == "kd" else 0
    out = replay.arrays["radiance" if key != "kd" else "kd"].grad.numpy()[row].astype(np.float64)
    if key == "kd" and s.materials[owner].ka_follows_kd:  # as backward() and r.params: ka is kd there
        out = out + replay.arrays["ka"].grad.numpy()[row]
    r.close()
    return out


@pytest.mark.parametrize("key, name, controls", [
    ("soft", "materials.ball.kd", ("cosine", "sample")), ("soft", "lights.0.radiance", ("emission",)),
    ("lamp", "materials.floor.kd", ("cosine",)), ("lamp", "materials.lamp.emission", ("emission",))])
def test_a_changed_replay_does_not(key, name, controls):
    """The controls: the emitter's cosine dropped, the first sample's weight, the emitter seen directly left
    out; each against the same differences that the unchanged replay, launched the same way, meets (the
    materials' kd gradients hold no emitted light: the samples' terms alone make them). Measured: the cosine
    dropped 0.21 and 0.21 off, the first sample's weight 0.32, the emitter left out 0.84 and 0.80."""
    s = SCENES[key]()
    w = weights_for(s)
    fd = component_differences(s, name, w, 1e-2)
    assert relative(replayed_gradient(s, w, name), fd) <= REL  # the harness itself is right
    changed = {"cosine": {"area_kernel": _no_cosine}, "sample": {"area_kernel": _first_sample},
               "emission": {"no_emission": True}}
    for control in controls:
        assert relative(replayed_gradient(s, w, name, **changed[control]), fd) > 20 * REL, control


@wp.kernel
def _terms(p: wp.array(dtype=wp.vec3), n: wp.array(dtype=wp.vec3), kd: wp.array(dtype=wp.vec3),
           ks: wp.array(dtype=wp.vec3), shininess: wp.array(dtype=float), point: wp.array(dtype=wp.vec3),
           normal: wp.array(dtype=wp.vec3), L_e: wp.array(dtype=wp.vec3), out: wp.array(dtype=wp.vec3)):
    i = wp.tid()
    hit = Surface()
    hit.p = p[i]
    hit.n = wp.normalize(n[i])
    k = Coefficients()
    k.kd = kd[i]
    k.ks = ks[i]
    out[i] = AREA_TERM(point_arrival(point[i], wp.normalize(normal[i]), hit), L_e[i], 0.05, k, shininess[i], hit.n,
                       wp.vec3(0.0, 0.6, 0.8))


def test_the_sample_term_passes_warps_gradcheck():
    """The forward's area-light sample term as the replay differentiates it (shading.point_arrival, then
    make_light_terms' area_term): its adjoints (the hit, its normal, colours, exponent, the sample's point and
    normal, L_e) against Warp's own finite differences, at hits lit from in front with a highlight and without."""
    rng = np.random.default_rng(1)
    arr = lambda a, grad=True: wp.array(np.asarray(a, np.float32), dtype=wp.vec3 if np.ndim(a) == 2 else float,  # noqa: E731
                                        requires_grad=grad)
    p = rng.uniform(-0.5, 0.5, (4, 3)) * [1, 0, 1]
    inputs = [arr(p), arr([[0.0, 1.0, 0.0], [0.1, 1.0, 0.0], [0.0, 1.0, 0.2], [-0.1, 1.0, 0.1]]),
              arr(rng.uniform(0.2, 0.8, (4, 3))), arr(rng.uniform(0.2, 0.8, (4, 3))), arr([8.0, 16.0, 4.0, 30.0]),
              arr([[0.3, 2.0, 0.4], [-0.2, 1.5, 0.6], [0.0, 2.5, 1.5], [0.5, 1.8, 1.0]]),
              arr([[0.0, -1.0, 0.1], [0.2, -1.0, 0.0], [0.0, -1.0, -0.3], [-0.1, -1.0, 0.0]]),
              arr(rng.uniform(1.0, 5.0, (4, 3)))]
    assert warp.autograd.gradcheck(_terms, dim=4, inputs=inputs, outputs=[wp.zeros(4, dtype=wp.vec3, requires_grad=True)],
                                   eps=1e-3, atol=2e-3, rtol=2e-3, show_summary=False, raise_exception=False)


def test_what_area_lights_hold_fixed_is_refused_in_one_line():
    """An emitting object's vertices (its sample points, the light's position and shape, are held fixed), an
    emission of 0 (no area light, no samples), and a record beyond memory (naming light_samples)."""
    s = lamp()
    r = warprt.Renderer(s)
    r.render(grad=True)
    w = weights_for(s)
    with pytest.raises(warprt.SceneError, match="objects.lamp.vertices.*area light.*held fixed"):
        r.backward(w, wrt=["objects.lamp.vertices"])
    assert "objects.lamp.vertices" not in r.backward(w) and "materials.lamp.emission" in r.backward(w)
    r.params["materials.lamp.emission"] = [0.0, 0.0, 0.0]
    r.render(grad=True)
    with pytest.raises(warprt.SceneError, match="materials.lamp.emission.*makes no area light"):
        r.backward(w, wrt=["materials.lamp.emission"])
    huge = soft(4096).with_camera(width=16384, height=16384)
    with pytest.raises(warprt.SceneError, match="render.light_samples or camera.width"):
        warprt.Renderer(huge).render(grad=True)
