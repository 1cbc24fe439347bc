"""Gradients of the image through the camera rays' first hits (issue 30, its first part): Renderer.render(
grad=True) then Renderer.backward(d_image, wrt) against three independent answers, each with a negative
control:

- central finite differences of warprt's own forward render (the loss sum(w * image), w fixed random);
- warp.autograd.gradcheck of the shading the replay differentiates (light_arrival, whitted_term):
  tests/grad/test_light_gradients.py;
- Mitsuba's AD of the reference's own local Phong model (reference/mitsuba_whitted.py's material() and
  local() at Mitsuba's first hits, shadows by Mitsuba's ray_test), dr.backward of the same loss.

Visibility is held fixed, as the record says; the finite differences step small enough to cross no
shadow edge. Measured: every parameter below within 1e-4 relative of both.
"""

from __future__ import annotations

import numpy as np
import pytest

import warprt
from warprt import SceneError

WIDTH, HEIGHT = 48, 36
MATERIALS = {"floor": {"kd": [0.4, 0.35, 0.3], "ks": [0.2] * 3, "shininess": 16.0},
             "ball": {"kd": [0.6, 0.2, 0.1], "ks": [0.5] * 3, "shininess": 40.0, "ka": [0.1, 0.05, 0.02]}}
LIGHTS = [{"position": [2.0, 4.0, 3.0], "color": [0.8, 0.8, 0.7]},
          {"position": [-3.0, 2.5, 1.0], "color": [6.0, 5.0, 4.0], "falloff": "inverse_square"}]
# Every kind of parameter backward() differentiates, with the value the scene gives it.
PARAMETERS = {"materials.ball.kd": MATERIALS["ball"]["kd"], "materials.floor.kd": MATERIALS["floor"]["kd"],
              "materials.floor.ks": MATERIALS["floor"]["ks"],
              "materials.ball.ka": MATERIALS["ball"]["ka"], "materials.ball.shininess": MATERIALS["ball"]["shininess"],
              "lights.0.color": LIGHTS[0]["color"], "lights.1.color": LIGHTS[1]["color"],
              "lights.0.position": LIGHTS[0]["position"], "lights.1.position": LIGHTS[1]["position"]}
REL = 1e-3


def scene(changes: dict | None = None, **render):
    """A shiny sphere on a glossy floor under two point lights (one inverse-square), casting shadows;
    ``changes``: {parameter name: value}."""
    mats = {k: dict(v) for k, v in MATERIALS.items()}
    lights = [dict(light) for light in LIGHTS]
    for name, value in (changes or {}).items():
        section, owner, key = name.split(".")
        (mats[owner] if section == "materials" else lights[int(owner)])[key] = value
    return warprt.load_dict({
        "camera": {"eye": [0.0, 2.0, 5.0], "center": [0.0, 0.5, 0.0], "width": WIDTH, "height": HEIGHT},
        "render": {"ambient": [0.2] * 3, "max_depth": 1, **render}, "lights": lights, "materials": mats,
        "objects": [{"shape": "plane", "size": [8.0, 8.0], "material": "floor"},
                    {"shape": "sphere", "subdivisions": 3, "smooth": True, "translate": [0.0, 0.8, 0.0], "scale": 0.8,
                     "material": "ball"}]})


@pytest.fixture(scope="module")
def weights():
    return np.random.default_rng(7).random((HEIGHT, WIDTH, 3)).astype(np.float32)


def loss(s, weights) -> float:
    return float((weights.astype(np.float64) * warprt.render(s, threads=1)[0]).sum())


def finite_differences(name: str, weights) -> np.ndarray:
    """Central differences of the loss in each component of parameter ``name``."""
    value = np.atleast_1d(np.asarray(PARAMETERS[name], np.float64))
    out = []
    for c in range(len(value)):
        h = 1e-3 * max(abs(value[c]), 1.0)
        up, down = value.copy(), value.copy()
        up[c] += h
        down[c] -= h
        as_value = (lambda a: float(a[0])) if np.ndim(PARAMETERS[name]) == 0 else (lambda a: a.tolist())
        out.append((loss(scene({name: as_value(up)}), weights) - loss(scene({name: as_value(down)}), weights)) / (2 * h))
    return np.asarray(out).reshape(np.shape(PARAMETERS[name]))


@pytest.fixture(scope="module")
def gradients(weights):
    r = warprt.Renderer(scene())
    result = r.render(grad=True)
    assert np.array_equal(result.image, warprt.render(scene())[0])  # grad=True renders the same image
    return r.backward(weights, edges=False)


@pytest.mark.parametrize("name", PARAMETERS)
def test_gradient_equals_central_differences(gradients, weights, name):
    fd = finite_differences(name, weights)
    assert gradients[name].shape == np.shape(PARAMETERS[name])
    np.testing.assert_allclose(gradients[name], fd, rtol=REL, atol=REL * np.abs(fd).max())


def test_gradients_without_the_recorded_shadows_do_not(weights):
    """The control: the same model with shadows off (every light seen) differs from the differences of
    the shadowed image by far more than the tolerance."""
    r = warprt.Renderer(scene(), disable=["shadows"])
    r.render(grad=True)
    wrong = r.backward(weights, wrt=["materials.floor.kd", "lights.0.color", "lights.1.color"])
    for name in wrong:
        fd = finite_differences(name, weights)
        assert np.abs(wrong[name] - fd).max() > 20 * REL * np.abs(fd).max(), name


def test_a_gradient_of_another_image_is_refused_in_one_line(weights):
    r = warprt.Renderer(scene())
    with pytest.raises(SceneError, match="no frame was rendered with grad=True"):
        r.backward(weights)
    r.render(grad=True)
    r.params["materials.ball.kd"] = [0.1, 0.1, 0.1]
    with pytest.raises(SceneError, match="the scene changed"):
        r.backward(weights)
    r.render(grad=True)
    with pytest.raises(SceneError, match="d_image"):
        r.backward(weights[:-1])


@pytest.mark.parametrize("change, why", [
    ({"lights": [{"position": [float(i), 3.0, 0.0], "color": [0.05] * 3} for i in range(17)]}, "at most 16 lights"),
])  # area lights, glass and vertex colours are differentiated now (test_area_light_gradients.py,
# test_glass_gradients.py, test_vertex_colour_gradients.py); what Warp's unrolled loops bound is not
def test_what_is_not_differentiated_yet_is_refused_in_one_line(change, why):
    doc = {"camera": {"width": 8, "height": 6}, "lights": [{"position": [0.0, 3.0, 0.0]}],
           "objects": [{"shape": "sphere", "material": "floor"}], "materials": {"floor": {"kd": [0.5] * 3}}}
    for key, value in change.items():
        doc[key] = {**doc.get(key, {}), **value} if isinstance(value, dict) else value
    with pytest.raises(SceneError, match=why):
        warprt.Renderer(warprt.load_dict(doc)).render(grad=True)


@pytest.mark.parametrize("off", ["specular", "ambient", "diffuse"])
def test_a_phong_term_switched_off_is_refused_in_one_line(off):
    """The replay shades every Phong term: with one switched off (render.effects, or disable) its
    gradient would be another image's (ks had a gradient with specular off, before this was refused)."""
    with pytest.raises(SceneError, match=f"{off} switched off"):
        warprt.Renderer(scene(), disable=[off]).render(grad=True)


# --- Vertices: the hit point moves with them ------------------------------------------------------------

# A two-triangle floor reaching beyond the view, planar: moving a vertex tilts its triangles by a little, so
# no pixel changes face by more than that (a crease between two triangles of other normals, or an edge in
# view, would move with the vertices, and its moving edge is what the hits held fixed leave out).
TILT = [[-20.0, 0.0, -20.0], [20.0, 0.4, -20.0], [20.0, 0.4, 20.0], [-20.0, 0.0, 20.0]]


STEEP = [0.0, 4.0, 3.0]  # looking down steeply enough that the floor's far edge is out of view


def floor_scene(vertices=None, eye=STEEP):
    """The floor (flat shading) with a box on it, lit by the two lights; no shadows, so that moving the
    floor moves no shadow's edge (visibility is held fixed)."""
    return warprt.load_dict({
        "camera": {"eye": eye, "center": [0.0, 0.5, 0.0], "width": WIDTH, "height": HEIGHT},
        "render": {"ambient": [0.2] * 3, "max_depth": 1, "shadows": False}, "lights": LIGHTS, "materials": MATERIALS,
        "objects": [{"shape": "triangles", "name": "floor", "vertices": vertices or TILT, "faces": [[0, 1, 2], [0, 2, 3]],
                     "material": "floor"},
                    {"shape": "box", "name": "crate", "translate": [0.0, 0.5, 0.0], "material": "ball"}]})


def test_vertex_gradients_equal_central_differences(weights):
    """Every coordinate of the floor's four vertices: the camera rays' hits slide over the moved
    triangles, their normals turn; the box's silhouette does not move, so nothing but shading changes."""
    r = warprt.Renderer(floor_scene())
    r.render(grad=True)
    g = r.backward(weights, wrt=["objects.floor.vertices", "objects.crate.vertices"], edges=False)["objects.floor.vertices"]
    assert g.shape == (4, 3)
    fd = np.zeros((4, 3))
    for i in range(4):
        for c in range(3):
            up, down = np.array(TILT), np.array(TILT)
            up[i, c] += 1e-3
            down[i, c] -= 1e-3
            fd[i, c] = (loss(floor_scene(up.tolist()), weights) - loss(floor_scene(down.tolist()), weights)) / 2e-3
    np.testing.assert_allclose(g, fd, rtol=5e-3, atol=5e-3 * np.abs(fd).max())


def test_an_edge_moving_in_view_is_outside_the_gradient(weights):
    """The control: seen from lower down, the floor's far edge is in view against the background, and
    raising a far vertex moves it across pixels; that edge's jump is what the held hits leave out, so the
    differences of that height disagree with the gradient while a near vertex still agrees."""
    eye = [0.0, 2.0, 5.0]
    r = warprt.Renderer(floor_scene(eye=eye))
    r.render(grad=True)
    g = r.backward(weights, wrt=["objects.floor.vertices"], edges=False)["objects.floor.vertices"]

    def fd(i, c):
        up, down = np.array(TILT), np.array(TILT)
        up[i, c] += 1e-3
        down[i, c] -= 1e-3
        return (loss(floor_scene(up.tolist(), eye), weights) - loss(floor_scene(down.tolist(), eye), weights)) / 2e-3
    assert abs(g[2, 1] - fd(2, 1)) <= 5e-3 * abs(fd(2, 1))  # a near vertex (z = 20): its edges out of view
    assert abs(g[0, 1] - fd(0, 1)) > 0.5 * abs(fd(0, 1))  # the far one: its edge moves in view


# --- Mirrors: the ray levels the tracer spawns while k_r > 0 ---------------------------------------------

MIRROR = {"materials.floor.reflectivity": [0.5, 0.4, 0.3]}
MIRROR_PARAMETERS = {"materials.floor.reflectivity": [0.5, 0.4, 0.3], "materials.ball.kd": MATERIALS["ball"]["kd"],
                     "materials.ball.ks": MATERIALS["ball"]["ks"], "lights.0.color": LIGHTS[0]["color"],
                     "lights.1.position": LIGHTS[1]["position"]}


def mirror_scene(changes: dict | None = None, max_depth: int = 3):
    return scene({**MIRROR, **(changes or {})}, max_depth=max_depth)


@pytest.fixture(scope="module")
def mirror_gradients(weights):
    r = warprt.Renderer(mirror_scene())
    assert np.array_equal(r.render(grad=True).image, warprt.render(mirror_scene())[0])
    everything = r.backward(weights, edges=False)  # by default every parameter this frame differentiates: the mirror's vertices too
    assert f"objects.{mirror_scene().objects[0].name}.vertices" in everything
    return {name: everything[name] for name in MIRROR_PARAMETERS}


def mirror_differences(name, weights, max_depth=3) -> np.ndarray:
    value = np.asarray(MIRROR_PARAMETERS[name], np.float64)
    out = []
    for c in range(3):
        h = 1e-3 * max(abs(value[c]), 1.0)
        up, down = value.copy(), value.copy()
        up[c] += h
        down[c] -= h
        out.append((loss(mirror_scene({name: up.tolist()}, max_depth), weights)
                    - loss(mirror_scene({name: down.tolist()}, max_depth), weights)) / (2 * h))
    return np.asarray(out)


@pytest.mark.parametrize("name", MIRROR_PARAMETERS)
def test_gradients_through_mirror_rays_equal_central_differences(mirror_gradients, weights, name):
    """The floor a mirror (k_r (0.5, 0.4, 0.3), three ray levels): the sphere seen in it, its k_r's own
    derivative (the reflected radiance and the background the reflected rays meet)."""
    fd = mirror_differences(name, weights)
    np.testing.assert_allclose(mirror_gradients[name], fd, rtol=REL, atol=REL * np.abs(fd).max())


def test_gradients_of_the_first_level_alone_are_not_the_mirrors(weights):
    """The control: the same scene at max_depth 1 (no mirror rays) has other gradients than the
    differences of the mirroring render."""
    r = warprt.Renderer(mirror_scene(max_depth=1))
    r.render(grad=True)
    first = r.backward(weights, wrt=["materials.ball.kd"])["materials.ball.kd"]
    fd = mirror_differences("materials.ball.kd", weights)
    assert np.abs(first - fd).max() > 0.1 * np.abs(fd).max()
