"""Gradients through Whitted's full ray tree with glass (issue 30): a dielectric's ior, transmittance and
absorption (materials.<name>.ior | transmittance | absorption), and the material colours, texels and lights
seen through it, through Fresnel (kernels.fresnel_dielectric), Snell (kernels.refract) and Beer (kernels.beer,
beer_forever), each called by the forward's dielectric_children and absorbed, which the replay differentiates.
The record is the forward's tree, written by its trace; the replay runs one differentiable launch per level
(kernels/replay.py). Held fixed: each ray's face, each shadow ray's visibility, the tree's
structure (which children exist, total internal reflection) and each ray's medium. Checked:

- the replayed image is the forward's to float32 rounding (the levels summed in another order), on a glass
  sphere over a textured floor (1 and 4 samples; the floor also a mirror; an area light too, its front seen
  through the ball), a prism with total internal reflection and the view from inside absorbing water (the
  camera in a medium);
- warp.autograd.gradcheck of fresnel_dielectric (both sides of the surface), refract and beer; its control, a
  Fresnel whose adjoint is dropped, fails it;
- central finite differences of the forward along random directions (tests/grad/directional.py, edges masked)
  on these scenes, relative error <= 1e-2; controls that fail: the gradient read along another direction,
  the gradient of a shallower tree, and the replay with Fresnel's or Beer's derivative dropped (their adjoints
  replaced by none, the kernels built again).

Measured (24 x 18): replay within 3e-6 of the forward's largest value; relative errors 2e-6 to 1.2e-3 (6e-3 for
the mirror's k_r at a step of 1e-3, float32 noise: 2.5e-5 at 1e-2, the step taken). The controls: 0.78 off
(the shallower tree), 0.37 and 1.0 off (Fresnel's and Beer's adjoints dropped), 7.8 and 4.4 off (another
direction).
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
import warp as wp
import warp.autograd

import warprt
from warprt import SceneError
from warprt.kernels import NO_RAY, beer, fresnel_dielectric, make_replay_level, refract
from warprt.scene import Texture, resolve_effects

from .directional import backward_masked, directional, random_direction

ROOT = Path(__file__).resolve().parents[2]
WIDTH, HEIGHT = 24, 18
REL = 1e-2
TEXELS = np.random.default_rng(1).uniform(0.1, 0.9, (8, 8, 3)).astype(np.float32)


def sphere(spp: int = 1, max_depth: int = 5, mirror: bool = False):
    """A glass sphere (ior 1.5, smooth normals, tinted and absorbing) over a floor with a bilinear image
    texture repeated 4 x 4, under a point light with shadows: the floor seen through the ball, upside down;
    with ``mirror``, the floor a weak mirror too (k_r 0.3: mirror rays in the tree, the ball in the floor)."""
    s = warprt.load_dict({
        "camera": {"eye": [0.031, 1.047, 4.5], "center": [0.0, 0.8, 0.0], "fovy": 35.0, "width": WIDTH,
                   "height": HEIGHT},
        "render": {"ambient": [0.2] * 3, "background": [0.05, 0.05, 0.08], "max_depth": max_depth, "spp": spp},
        "lights": [{"position": [3.0, 5.0, 4.0], "color": [0.8, 0.8, 0.8]}],
        "materials": {"glass": {"ior": 1.5, "ka": [0, 0, 0], "kd": [0, 0, 0], "ks": [0.6] * 3, "shininess": 200.0,
                                "transmittance": [0.9, 0.95, 0.85], "absorption": [0.3, 0.1, 0.05]},
                      "floor": {"kd": [0.6, 0.6, 0.6], "kd_texture": {"checker": [[1, 1, 1], [0.5, 0.5, 0.5]]}}},
        "objects": [{"shape": "sphere", "radius": 0.8, "subdivisions": 3, "smooth": True, "material": "glass",
                     "translate": [0.0, 0.8, 0.0]},
                    {"shape": "plane", "size": [20.0, 20.0], "material": "floor"}]})
    mats = dict(s.materials)
    texture = Texture(image=TEXELS, uv_transform=(4.0, 0.0, 0.0, 0.0, 4.0, 0.0))
    mats["floor"] = replace(mats["floor"], kd_texture=texture,
                            reflectivity=(0.3, 0.25, 0.2) if mirror else (0.0, 0.0, 0.0))
    return replace(s, materials=mats)


def prism():
    """scenes/prism_tir.toml at 24 x 18: the right-angle prism's hypotenuse reflects totally in the middle of
    the view and lets the rays through towards the edges; its glass tinted and absorbing here, the red panel
    given some green and blue (so that a random step keeps it non-negative)."""
    s = warprt.load_scene(ROOT / "scenes" / "prism_tir.toml").with_camera(width=WIDTH, height=HEIGHT)
    mats = dict(s.materials)
    mats["glass"] = replace(mats["glass"], transmittance=(0.95, 0.9, 0.92), absorption=(0.2, 0.05, 0.1))
    mats["red"] = replace(mats["red"], kd=(0.9, 0.2, 0.1))
    return replace(s, materials=mats)


def area_lit():
    """The glass sphere with a rectangular area light too (4 sample points), behind the ball and facing the
    camera: its front seen directly and through the ball, its light on the floor seen through it."""
    s = sphere()
    area = warprt.load_dict({"lights": [{"type": "area", "shape": "rectangle", "center": [0.3, 1.6, -2.0],
                                         "normal": [0.0, -0.6, 1.0], "size": [1.0, 0.8], "radiance": [5.0, 4.5, 4.0]}],
                             "objects": [{"shape": "sphere"}]})
    return replace(s, lights=list(s.lights) + list(area.lights)).with_render(light_samples=4)


def inside():
    """scenes/inside_glass.toml at 24 x 18: the eye inside a box of absorbing water, Snell's window ahead."""
    return warprt.load_scene(ROOT / "scenes" / "inside_glass.toml").with_camera(width=WIDTH, height=HEIGHT)


def coloured():
    """The glass sphere over a floor with vertex colours (a colour per corner, kd and ka times their
    interpolation at the hit), seen directly and through the ball."""
    s = sphere()
    floor = s.objects[1]
    colors = np.random.default_rng(2).uniform(0.3, 1.0, (len(floor.vertices), 3))
    return replace(s, objects=[s.objects[0], replace(floor, colors=colors)])


SCENES = {"sphere": sphere, "prism": prism, "inside": inside, "mirror": lambda: sphere(mirror=True), "area": area_lit,
          "spp4": lambda: sphere(spp=4), "coloured": coloured}


@pytest.fixture(scope="module")
def weights():
    return np.random.default_rng(5).random((HEIGHT, WIDTH, 3)).astype(np.float32)


def _span(hits, k: int) -> tuple:
    """(first, last) entries of ray level k of a record."""
    first, count = hits.level(k)
    return first, first + count


def replayed(s):
    r = warprt.Renderer(s)
    forward = r.render().image
    geom = r.geometry
    hits = warprt.image.record_first_hits(s, geom, geom.scene_data(s), resolve_effects(s), "cpu")
    image = warprt.image.replay_image(s, geom, hits, "cpu")
    r.close()
    return forward, image, hits


@pytest.mark.parametrize("name, spp", [("sphere", 1), ("sphere", 4), ("prism", 1), ("inside", 1), ("mirror", 1),
                                        ("area", 1), ("coloured", 1)])
def test_the_replayed_tree_is_the_forward_image(name, spp):
    s = SCENES[name]() if spp == 1 else sphere(spp)
    forward, image, hits = replayed(s)
    assert hits.tree
    face, first = hits.rec.face.numpy(), hits.level(1)[0]
    parent = hits.rec.parent.numpy()[np.flatnonzero(face[first:hits.entries] != NO_RAY) + first]
    levels = [k for k in range(hits.levels) if (face[slice(*_span(hits, k))] != NO_RAY).any()]
    assert len(levels) >= 4 and (np.unique(parent // 2, return_counts=True)[1] == 2).any()  # rays with both children
    assert np.abs(image - forward).max() <= 1e-5 * np.abs(forward).max()


def test_render_with_grad_is_the_same_image():
    r = warprt.Renderer(prism())
    assert np.array_equal(r.render(grad=True).image, warprt.render(prism())[0])
    r.close()


# --- The functions: Warp's gradcheck ---------------------------------------------------------------------

@wp.kernel
def _fresnel(cos_i: wp.array(dtype=float), eta: wp.array(dtype=float), out: wp.array(dtype=float)):
    i = wp.tid()
    out[i] = fresnel_dielectric(cos_i[i], eta[i])


@wp.kernel
def _refract(d: wp.array(dtype=wp.vec3), n: wp.array(dtype=wp.vec3), eta: wp.array(dtype=float),
             out: wp.array(dtype=wp.vec3)):
    i = wp.tid()
    t, transmits = refract(d[i], n[i], eta[i])
    out[i] = t


@wp.kernel
def _beer(w: wp.array(dtype=wp.vec3), sigma: wp.array(dtype=wp.vec3), distance: wp.array(dtype=float),
          out: wp.array(dtype=wp.vec3)):
    i = wp.tid()
    out[i] = beer(w[i], sigma[i], distance[i])


@wp.func
def _fresnel_held(cos_i: float, eta: float) -> float:
    """fresnel_dielectric with its adjoint dropped (F held): the controls' wrong derivative."""
    return fresnel_dielectric(cos_i, eta)


@wp.func_grad(_fresnel_held)
def _adj_fresnel_held(cos_i: float, eta: float, adj_ret: float):
    pass


@wp.func
def _beer_held(weight: wp.vec3, sigma: wp.vec3, distance: float) -> wp.vec3:
    """beer with its adjoint dropped: the controls' wrong derivative."""
    return beer(weight, sigma, distance)


@wp.func_grad(_beer_held)
def _adj_beer_held(weight: wp.vec3, sigma: wp.vec3, distance: float, adj_ret: wp.vec3):
    pass


@wp.kernel
def _fresnel_without_adjoint(cos_i: wp.array(dtype=float), eta: wp.array(dtype=float), out: wp.array(dtype=float)):
    i = wp.tid()
    out[i] = _fresnel_held(cos_i[i], eta[i])


def check(kernel, inputs, outputs) -> bool:
    return warp.autograd.gradcheck(kernel, dim=len(outputs[0]), inputs=inputs, outputs=outputs, eps=1e-3, atol=2e-3,
                                   rtol=2e-3, show_summary=False, raise_exception=False)


# Entering (cos_i > 0, eta) and leaving (cos_i < 0, 1 / eta), away from the critical angle's kink.
COS = [0.95, 0.6, 0.25, -0.97, -0.9]
ETA = [1.5, 1.33, 1.7, 1.5, 1.4]


def test_fresnel_refract_and_beer_pass_warps_gradcheck():
    f = lambda values: wp.array(values, dtype=float, requires_grad=True)  # noqa: E731
    assert check(_fresnel, [f(COS), f(ETA)], [wp.zeros(5, dtype=float, requires_grad=True)])
    d = np.array([[0.3, -0.9, 0.1], [-0.6, -0.7, 0.2], [0.0, -1.0, 0.0], [0.5, -0.5, -0.4]])
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    n = np.array([[0.0, 1.0, 0.0], [0.2, 0.9, 0.1], [0.1, 0.99, 0.0], [0.0, 0.8, -0.2]])
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    v = lambda values: wp.array(values, dtype=wp.vec3, requires_grad=True)  # noqa: E731
    assert check(_refract, [v(d), v(n), f([1.5, 1.2, 1.0 / 1.5, 1.33])],
                 [wp.zeros(4, dtype=wp.vec3, requires_grad=True)])
    assert check(_beer, [v([[0.9, 0.5, 0.2], [1.0, 1.0, 1.0]]), v([[0.3, 0.1, 0.0], [2.0, 0.5, 1.0]]), f([0.7, 1.9])],
                 [wp.zeros(2, dtype=wp.vec3, requires_grad=True)])


def test_a_fresnel_without_its_adjoint_fails_gradcheck():
    """The control: the same check of a Fresnel whose adjoint is dropped."""
    f = lambda values: wp.array(values, dtype=float, requires_grad=True)  # noqa: E731
    assert not check(_fresnel_without_adjoint, [f(COS), f(ETA)], [wp.zeros(5, dtype=float, requires_grad=True)])


# --- The image: central differences of the forward -------------------------------------------------------

CHECKS = [("sphere", "materials.glass.ior"), ("sphere", "materials.glass.transmittance"),
          ("sphere", "materials.glass.absorption"), ("sphere", "materials.floor.kd"),
          ("sphere", "materials.floor.kd_texture"), ("sphere", "lights.0.color"), ("sphere", "materials.glass.ks"),
          ("sphere", "camera.fovy"), ("mirror", "materials.glass.ior"), ("mirror", "materials.floor.reflectivity"),
          ("prism", "materials.glass.ior"), ("prism", "materials.glass.transmittance"),
          ("prism", "materials.glass.absorption"), ("prism", "materials.red.kd"), ("prism", "lights.0.position"),
          ("inside", "materials.water.ior"), ("inside", "materials.water.absorption"),
          ("area", "lights.1.radiance"), ("area", "materials.glass.transmittance"),
          ("area", "materials.glass.absorption"), ("spp4", "materials.glass.ior"),
          # vertices through the tree: the hits on the moved faces, the smooth sphere's normals made from them
          ("prism", "objects.prism.vertices"), ("sphere", "objects.sphere.vertices"),
          ("sphere", "objects.plane.vertices"), ("area", "lights.1.center"), ("coloured", "objects.plane.colors"),
          ("coloured", "materials.floor.kd")]


# Nearly linear in k_r (a path meets the floor once, mostly): a wider step lowers float32's noise, which at
# 1e-3 is 6e-3 of this loss's small derivative along the step.
WIDER = {"materials.floor.reflectivity": 1e-2}


def step(s, name: str, seed: int = 3) -> dict:
    """A random step: an ior's a tenth of its size (so that few pixels cross the critical angle), the
    vertices' too (each vertex moved on its own: the faces' normals turn fast)."""
    return random_direction(s, [name], seed=seed, rel=0.1 if name.endswith((".ior", ".vertices")) else 1.0)


@pytest.fixture(scope="module")
def checks(weights):
    out = {}
    for scene_name, name in CHECKS:
        s = SCENES[scene_name]()
        d = directional(s, step(s, name), weights, h=WIDER.get(name, 1e-3))
        out[scene_name, name] = (d, backward_masked(s, weights, d))
    return out


@pytest.mark.parametrize("scene_name, name", CHECKS)
def test_glass_gradients_equal_central_differences(checks, scene_name, name):
    d, grads = checks[scene_name, name]
    assert d.masked < 0.1
    assert d.error(grads) <= REL, (d.gradient(grads), d.fd)


@pytest.mark.parametrize("scene_name, name", [("sphere", "materials.glass.transmittance"),
                                              ("prism", "materials.glass.absorption"),
                                              ("sphere", "objects.sphere.vertices"),
                                              ("area", "lights.1.center"),
                                              ("coloured", "objects.plane.colors")])
def test_a_gradient_along_another_direction_does_not(checks, scene_name, name):
    """The control: the gradient read along another random step than the differences took."""
    d, grads = checks[scene_name, name]
    other = step(SCENES[scene_name](), name, seed=8)[name]
    assert abs((grads[name] * other).sum() - d.fd) > 0.1 * abs(d.fd)


def test_the_gradient_of_a_shallower_tree_does_not(checks, weights):
    """The control: the ior's gradient of the prism's tree cut at three levels (the rays the hypotenuse
    reflects totally never leave the prism for the red panel) is not the differences of the six-level tree
    (measured: 0.78 off)."""
    d, _ = checks["prism", "materials.glass.ior"]
    shallow = backward_masked(prism().with_render(max_depth=3), weights, d)
    assert d.error(shallow) > 0.3


@pytest.fixture
def held(monkeypatch):
    """Replay kernels built with a function's adjoint dropped (``held(name)``: the forward's fresnel_dielectric
    or beer, which its dielectric_children and absorbed call, replaced by the held copy, the same value), the
    replay's kernels' cache emptied before and after."""
    make_replay_level.cache_clear()

    def hold(name: str):
        monkeypatch.setattr(f"warprt.kernels.dielectric.{name}", {"fresnel_dielectric": _fresnel_held,
                                                                   "beer": _beer_held}[name])

    yield hold
    monkeypatch.undo()
    make_replay_level.cache_clear()


@pytest.mark.parametrize("function, scene_name, name", [("fresnel_dielectric", "sphere", "materials.glass.ior"),
                                                        ("beer", "prism", "materials.glass.absorption")])
def test_a_replay_without_fresnels_or_beers_derivative_does_not(checks, weights, held, function, scene_name, name):
    """The controls: Fresnel's F held (the ior's derivative by Snell alone) or Beer's factor held (no
    absorption derivative at all) leave the gradient far from the differences."""
    d, _ = checks[scene_name, name]
    held(function)
    assert d.error(backward_masked(SCENES[scene_name](), weights, d)) > 0.1


# --- A transmittance of 0: the refracted rays the forward leaves out ---------------------------------------

def sheet(transmittance):
    """An open glass sheet (one interface: the light through it is linear in its transmittance) in front of a
    lit panel, the light between them."""
    return warprt.load_dict({
        "camera": {"eye": [0.3, 0.6, 5.0], "center": [0.0, 0.3, 0.0], "fovy": 40.0, "width": WIDTH, "height": HEIGHT},
        "render": {"ambient": [0.1] * 3, "background": [0.05, 0.05, 0.08], "max_depth": 3},
        "lights": [{"position": [0.5, 1.5, 0.0], "color": [0.9, 0.9, 0.8]}],
        "materials": {"glass": {"ior": 1.5, "ka": [0, 0, 0], "kd": [0, 0, 0], "ks": [0.5] * 3, "shininess": 100.0,
                                "transmittance": list(transmittance)},
                      "panel": {"kd": [0.8, 0.5, 0.3], "ks": [0.3] * 3, "shininess": 20.0}},
        "objects": [{"shape": "triangles", "name": "sheet", "vertices": [[-3, -2, 1], [3, -2, 1], [3, 3, 1], [-3, 3, 1]],
                     "faces": [[0, 1, 2], [0, 2, 3]], "material": "glass"},
                    {"shape": "box", "size": [6.0, 6.0, 0.2], "translate": [0.0, 0.5, -1.0], "material": "panel"}]})


@pytest.mark.filterwarnings("ignore:.*not closed")
def test_a_transmittance_of_0_gets_its_true_derivative(weights):
    """At a transmittance of 0 the forward traces no refracted ray (it would carry nothing), but the
    derivative in that transmittance is what such a ray would see: the record follows those rays (weight 0,
    the image unchanged) and the gradient equals the one-sided differences towards positive values (the
    image is linear in it here). The control: the forward's own tree, without those rays, would give 0."""
    r = warprt.Renderer(sheet((0.0, 0.0, 0.0)))
    image = r.render(grad=True).image
    assert np.array_equal(image, warprt.render(sheet((0.0, 0.0, 0.0)))[0])
    g = r.backward(weights, wrt=["materials.glass.transmittance"], edges=False)["materials.glass.transmittance"]
    u = np.random.default_rng(3).uniform(0.2, 1.0, 3)
    h = 1e-2
    fd = float(((warprt.render(sheet(h * u))[0].astype(np.float64) - image) * weights).sum()) / h
    assert abs(float(g @ u) - fd) <= 1e-3 * abs(fd)
    assert abs(fd) > 10.0  # the control: 0, the forward's own tree's answer, is far off (measured: 66.6)


# --- What a tree costs, and what stays refused -----------------------------------------------------------

def test_a_tree_too_big_for_memory_is_refused_in_one_line(monkeypatch):
    """The record counts the tree as it grows: with room for the first levels' check (up front, a chain)
    but not for the tree, one error naming the settings that make it smaller."""
    calls = []

    def little(device="cpu"):
        calls.append(device)
        return (10**12 if len(calls) == 1 else 20_000), "left in this test"

    monkeypatch.setattr("warprt.image.grad_record.available_memory", little)
    with pytest.raises(SceneError, match="ray tree.*render.max_depth"):
        warprt.Renderer(sphere()).render(grad=True)


def test_the_area_lights_front_is_met_through_the_glass():
    """The area-light scene's tree: rays that meet the emitter's front, seen directly and through the ball."""
    _, _, hits = replayed(area_lit())
    emit, face = hits.rec.emit.numpy(), hits.rec.face.numpy()
    met = [int(((emit[slice(*_span(hits, k))] >= 0) & (face[slice(*_span(hits, k))] >= 0)).sum())
           for k in range(hits.levels)]
    assert hits.words > 0 and met[0] > 0 and sum(met[1:]) > 0


def test_a_reflectivity_of_0_gets_its_true_derivative_through_the_tree(weights):
    """The floor under the glass sphere has k_r 0: render(grad=[its reflectivity]) records its mirror rays and
    what they spawn (the ball's tree seen in the floor, weight 0: the image unchanged), and the gradient equals
    the one-sided differences towards positive values (the image is linear in k_r for a fixed tree). The
    control: grad=True, which records no such rays, is refused by backward and left out of its defaults."""
    name = "materials.floor.reflectivity"
    s = sphere()
    r = warprt.Renderer(s)
    image = r.render(grad=[name]).image
    assert np.array_equal(image, warprt.render(s)[0])
    g = r.backward(weights, wrt=[name], edges=False)[name]
    u = np.random.default_rng(3).uniform(0.2, 1.0, 3)
    h = 1e-2
    floor = replace(s.materials["floor"], reflectivity=tuple(h * u))
    stepped = warprt.render(replace(s, materials={**s.materials, "floor": floor}))[0]
    fd = float(((stepped.astype(np.float64) - image) * weights).sum()) / h
    assert abs(float(g @ u) - fd) <= 2e-3 * abs(fd) and abs(fd) > 1.0, (float(g @ u), fd)
    r.render(grad=True)
    with pytest.raises(SceneError, match="render with grad="):
        r.backward(weights, wrt=[name])
    assert name not in r.backward(weights, edges=False)
    r.close()
