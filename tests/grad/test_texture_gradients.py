"""Gradients with respect to image textures' texels (materials.<name>.ka_texture | kd_texture | ks_texture,
(H, W, 3) with row 0 the image's top, as r.params has them). The forward samples a wp.Texture2D, which gives
texels no adjoint; the replay reads the same texels from a wp.array through kernels.bilinear, Warp's CPU
sampler's arithmetic (its wrap, clamp and mirror addressing) written out. Checked:

- bilinear equals wp.texture_sample itself at random coordinates inside and outside [0, 1), for every pair
  of wrap modes, and passes warp.autograd.gradcheck (texels and coordinates);
- the replayed image is the forward's (a floor's kd texture repeated 3 x 3 times, ka following it; a
  sphere's kd texture mirrored/clamped and ks texture clamped/mirrored, under a map that reaches outside
  [0, 1]);
- directional derivatives along random directions over all texels, and over four texels, equal central
  finite differences of the forward (the image is linear in each texel: h = 1e-2);
- controls: the gradient read at other texels, read upside down, and kd's without the ka that follows it.

Measured: replay equal to the bit; bilinear equal to wp.texture_sample to the bit; relative errors
2e-6 to 8.3e-5 (every texel and four of them, each texture).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
import warp as wp
import warp.autograd

import warprt
from warprt.geometry import TEXTURE_CLAMP, TEXTURE_MIRROR, TEXTURE_WRAP
from warprt.kernels import bilinear
from warprt.scene import Material, Texture, resolve_effects

from .directional import backward_masked, directional, random_direction

WIDTH, HEIGHT = 24, 18
REL = 2e-3
H = 1e-2  # the image is linear in each texel: a wider step only lowers float32's noise
_rng = np.random.default_rng(2)
FLOOR_TEXELS = _rng.uniform(0.2, 1.0, (5, 6, 3)).astype(np.float32)
BALL_TEXELS = _rng.uniform(0.2, 1.0, (4, 7, 3)).astype(np.float32)
NAMES = ["materials.floor.kd_texture", "materials.floor.ka_texture", "materials.ball.kd_texture",
         "materials.ball.ks_texture"]


def textured(spp: int = 1):
    """A floor (kd texture repeated 3 x 3, ka following kd, a weak mirror) and a uv sphere (kd texture
    mirrored along u and clamped along v, ks texture the other way round, both mapped to reach outside
    [0, 1]) under a point light, with shadows, two levels."""
    checker = {"checker": [[1, 1, 1], [0.5, 0.5, 0.5]]}  # stand-ins, so that the shapes get their uvs
    s = warprt.load_dict({
        "camera": {"eye": [0.0, 2.0, 5.0], "center": [0.0, 0.5, 0.0], "width": WIDTH, "height": HEIGHT},
        "render": {"ambient": [0.2] * 3, "max_depth": 2, "spp": spp},
        "lights": [{"position": [2.0, 4.0, 3.0], "color": [0.9, 0.9, 0.8]}],
        "materials": {"floor": {"kd_texture": checker}, "ball": {"kd_texture": checker, "ks_texture": checker}},
        "objects": [{"shape": "plane", "size": [8.0, 8.0], "material": "floor"},
                    {"shape": "uv_sphere", "smooth": True, "translate": [0.0, 0.8, 0.0], "radius": 0.8,
                     "material": "ball"}]})
    mats = dict(s.materials)
    mats["floor"] = Material(kd=(0.9, 0.8, 0.7), ks=(0.2,) * 3, shininess=16.0, reflectivity=(0.2,) * 3,
                             kd_texture=Texture(image=FLOOR_TEXELS, uv_transform=(3.0, 0.0, 0.25, 0.0, 3.0, -0.1)))
    mats["ball"] = Material(kd=(0.8, 0.5, 0.4), ka=(0.1, 0.1, 0.1), ks=(0.8,) * 3, shininess=20.0,
                            kd_texture=Texture(image=BALL_TEXELS, uv_transform=(1.5, 0.0, -0.25, 0.0, 1.5, -0.25),
                                               wrap=("mirror", "clamp")),
                            ks_texture=Texture(image=np.ascontiguousarray(BALL_TEXELS[::-1]),
                                               uv_transform=(1.2, 0.0, -0.1, 0.0, 1.2, -0.1), wrap=("clamp", "mirror")))
    return replace(s, materials=mats)


@pytest.fixture(scope="module")
def weights():
    return np.random.default_rng(5).random((HEIGHT, WIDTH, 3)).astype(np.float32)


# --- The lookup: Warp's sampler, with adjoints -----------------------------------------------------------

@wp.kernel
def _lookups(texture: wp.Texture2D, texels: wp.array(dtype=wp.vec3), width: int, height: int, wrap_u: int,
             wrap_v: int, q: wp.array(dtype=wp.vec2), sampled: wp.array(dtype=wp.vec3), ours: wp.array(dtype=wp.vec3)):
    i = wp.tid()
    t = wp.texture_sample(texture, q[i], dtype=wp.vec4)
    sampled[i] = wp.vec3(t[0], t[1], t[2])
    ours[i] = bilinear(texels, 0, width, height, wrap_u, wrap_v, q[i])


ADDRESS = {TEXTURE_WRAP: wp.TextureAddressMode.WRAP, TEXTURE_CLAMP: wp.TextureAddressMode.CLAMP,
           TEXTURE_MIRROR: wp.TextureAddressMode.MIRROR}


@pytest.mark.parametrize("wrap_u", list(ADDRESS))
@pytest.mark.parametrize("wrap_v", list(ADDRESS))
def test_bilinear_is_warps_texture_sample(wrap_u, wrap_v):
    """At 2,000 random coordinates in [-2.5, 2.5)^2 and at texel centres and edges, the RGB of an RGBA
    Texture2D (LINEAR, normalised coordinates, the forward's) and bilinear over the same texels agree."""
    h, w = BALL_TEXELS.shape[:2]
    rgba = np.concatenate([BALL_TEXELS, np.ones((h, w, 1), np.float32)], -1)
    texture = wp.Texture2D(rgba, filter_mode=wp.TextureFilterMode.LINEAR, address_mode_u=ADDRESS[wrap_u],
                           address_mode_v=ADDRESS[wrap_v], normalized_coords=True)
    grid = np.stack(np.meshgrid(np.arange(-w, 2 * w + 1) / (2 * w), np.arange(-h, 2 * h + 1) / (2 * h)), -1).reshape(-1, 2)
    q = np.concatenate([np.random.default_rng(1).uniform(-2.5, 2.5, (2000, 2)), grid]).astype(np.float32)
    n = len(q)
    sampled, ours = wp.zeros(n, dtype=wp.vec3), wp.zeros(n, dtype=wp.vec3)
    wp.launch(_lookups, dim=n, inputs=[texture, wp.array(BALL_TEXELS.reshape(-1, 3), dtype=wp.vec3), w, h, wrap_u,
                                       wrap_v, wp.array(q, dtype=wp.vec2), sampled, ours])
    assert np.abs(sampled.numpy() - ours.numpy()).max() <= 1e-6


def test_bilinear_with_the_wrong_row_order_is_not():
    """The control: the texels upside down (row 0 at the top, as r.params shows them) are another image."""
    h, w = BALL_TEXELS.shape[:2]
    rgba = np.concatenate([BALL_TEXELS, np.ones((h, w, 1), np.float32)], -1)
    texture = wp.Texture2D(rgba, filter_mode=wp.TextureFilterMode.LINEAR, normalized_coords=True,
                           address_mode_u=wp.TextureAddressMode.WRAP, address_mode_v=wp.TextureAddressMode.WRAP)
    q = np.random.default_rng(1).uniform(0.0, 1.0, (200, 2)).astype(np.float32)
    sampled, ours = wp.zeros(200, dtype=wp.vec3), wp.zeros(200, dtype=wp.vec3)
    flipped = wp.array(np.ascontiguousarray(BALL_TEXELS[::-1]).reshape(-1, 3), dtype=wp.vec3)
    wp.launch(_lookups, dim=200, inputs=[texture, flipped, w, h, TEXTURE_WRAP, TEXTURE_WRAP, wp.array(q, dtype=wp.vec2),
                                         sampled, ours])
    assert np.abs(sampled.numpy() - ours.numpy()).max() > 0.1


@wp.kernel
def _bilinear(texels: wp.array(dtype=wp.vec3), q: wp.array(dtype=wp.vec2), wrap: wp.array(dtype=wp.vec2i),
              out: wp.array(dtype=wp.vec3)):
    i = wp.tid()
    out[i] = bilinear(texels, 0, 7, 4, wrap[i][0], wrap[i][1], q[i])


def test_bilinear_passes_warps_gradcheck():
    """Adjoints of the texels and of the coordinates, for each wrap mode, at coordinates at least 1e-2
    texel from a texel centre or a wrap seam (where the bilinear lookup has a kink)."""
    q = [[0.31, 0.42], [-0.37, 1.33], [1.61, -0.27], [0.93, 0.07], [2.21, -1.29], [0.55, 0.71]]
    modes = [(TEXTURE_WRAP, TEXTURE_WRAP), (TEXTURE_MIRROR, TEXTURE_CLAMP), (TEXTURE_CLAMP, TEXTURE_MIRROR),
             (TEXTURE_WRAP, TEXTURE_MIRROR), (TEXTURE_MIRROR, TEXTURE_WRAP), (TEXTURE_CLAMP, TEXTURE_CLAMP)]
    inputs = [wp.array(BALL_TEXELS.reshape(-1, 3), dtype=wp.vec3, requires_grad=True),
              wp.array(np.asarray(q, np.float32), dtype=wp.vec2, requires_grad=True),
              wp.array(np.asarray(modes, np.int32), dtype=wp.vec2i)]
    assert warp.autograd.gradcheck(_bilinear, dim=len(q), inputs=inputs, outputs=[wp.zeros(len(q), dtype=wp.vec3,
                                                                                          requires_grad=True)],
                                   eps=1e-4, atol=2e-3, rtol=2e-3, show_summary=False, raise_exception=False)


# --- The image ----------------------------------------------------------------------------------------

@pytest.mark.parametrize("spp", [1, 4])
def test_the_replayed_image_is_the_forward_image(spp):
    s = textured(spp)
    r = warprt.Renderer(s)
    forward = r.render().image
    geom = r.geometry
    hits = warprt.image.record_first_hits(s, geom, geom.scene_data(s), resolve_effects(s), "cpu")
    assert np.abs(warprt.image.replay_image(s, geom, hits, "cpu") - forward).max() <= 4e-7 * np.abs(forward).max()


def test_every_image_texture_is_a_parameter(weights):
    r = warprt.Renderer(textured())
    r.render(grad=True)
    g = r.backward(weights, edges=False)
    for name in NAMES:
        assert g[name].shape == r.params[name].shape, name
    assert np.abs(g["materials.ball.ks_texture"]).max() > 0


@pytest.fixture(scope="module")
def checks(weights):
    """{name: (Directional over all its texels, the same over four, their gradients)}; the four texels are
    the ones the loss depends on most (the largest gradients of a first backward(): a specular texture is
    seen through a few texels only), moved along a random direction."""
    s = textured()
    r = warprt.Renderer(s)
    r.render(grad=True)
    first = r.backward(weights, wrt=NAMES, edges=False)
    out = {}
    for name in NAMES:
        size = np.abs(first[name]).sum(-1)
        few = np.zeros(size.shape + (1,))
        few.reshape(-1)[np.argsort(size, axis=None)[-4:]] = 1.0
        every = directional(s, random_direction(s, [name], rel=0.2), weights, h=H)
        four = directional(s, random_direction(s, [name], seed=4, only={name: few}), weights, h=H)
        out[name] = (every, backward_masked(s, weights, every), four, backward_masked(s, weights, four))
    return out


@pytest.mark.parametrize("name", NAMES)
def test_texel_gradients_equal_central_differences(checks, name):
    every, g_every, four, g_four = checks[name]
    assert every.masked < 0.05 and four.masked < 0.05
    assert every.error(g_every) <= REL, (every.gradient(g_every), every.fd)
    assert four.fd != 0.0 and four.error(g_four) <= REL, (four.gradient(g_four), four.fd)


@pytest.mark.parametrize("name", NAMES)
def test_texel_gradients_read_at_other_texels_do_not(checks, name):
    """The control: the four texels' gradient read at the texels half the image away (wrapping; a next
    neighbour has nearly the same gradient where the texture is magnified). Measured: 0.86 to 1.0 off."""
    _, _, four, g_four = checks[name]
    h, w = g_four[name].shape[:2]
    shifted = np.roll(g_four[name], (h // 2, w // 2), axis=(0, 1))
    assert abs((shifted * four.direction[name]).sum() - four.fd) > 0.5 * abs(four.fd)


@pytest.mark.parametrize("name", ["materials.floor.kd_texture", "materials.ball.ks_texture"])
def test_texel_gradients_read_upside_down_do_not(checks, name):
    """The control: the gradient over every texel read with its rows upside down (the texture's storage
    order, row 0 at v = 0, where r.params has row 0 at the top). Measured: 0.74 and 0.30 off (the sphere's
    kd texture, half of it seen and mirrored along u, only 0.05: not a control)."""
    every, g_every, _, _ = checks[name]
    assert abs((g_every[name][::-1] * every.direction[name]).sum() - every.fd) > 0.2 * abs(every.fd)


def test_kd_texture_carries_the_ka_texture_that_follows_it(checks, weights):
    """The floor's ka texture follows its kd texture (the file left ka out): r.params moves both with
    kd_texture, so its gradient holds ka_texture's too; the control: kd's own term alone (less ka's)."""
    every, g_every, _, _ = checks["materials.floor.kd_texture"]
    ka_term = backward_masked(textured(), weights, replace(every, direction={"materials.floor.ka_texture": 0}))
    kd_alone = g_every["materials.floor.kd_texture"] - ka_term["materials.floor.ka_texture"]
    assert abs((kd_alone * every.direction["materials.floor.kd_texture"]).sum() - every.fd) > 20 * REL * abs(every.fd)


def textured_floor():
    """The tilted two-triangle floor of the vertex tests (its edges out of view, no shadows) with uvs and a
    kd texture repeated 4 x 4 over it, and the box on it."""
    from .test_first_hit_gradients import LIGHTS, MATERIALS, STEEP, TILT

    checker = {"checker": [[1, 1, 1], [0.5, 0.5, 0.5]]}
    s = warprt.load_dict({
        "camera": {"eye": STEEP, "center": [0.0, 0.5, 0.0], "width": WIDTH, "height": HEIGHT},
        "render": {"ambient": [0.2] * 3, "max_depth": 1, "shadows": False}, "lights": LIGHTS,
        "materials": {**MATERIALS, "floor": {"kd_texture": checker}},
        "objects": [{"shape": "triangles", "name": "floor", "vertices": TILT, "faces": [[0, 1, 2], [0, 2, 3]],
                     "uv": [[0, 0], [1, 0], [1, 1], [0, 1]], "material": "floor"},
                    {"shape": "box", "name": "crate", "translate": [0.0, 0.5, 0.0], "material": "ball"}]})
    mats = dict(s.materials)
    mats["floor"] = Material(kd=(0.9, 0.8, 0.7), ks=(0.2,) * 3, shininess=16.0,
                             kd_texture=Texture(image=FLOOR_TEXELS, uv_transform=(4.0, 0.0, 0.0, 0.0, 4.0, 0.0)))
    return replace(s, materials=mats)


def test_vertex_gradients_through_the_texture_equal_central_differences(weights):
    """Moving the floor's vertices slides each hit's uv over the texture too. Measured: 2.4e-3 relative
    (the untextured floor 3.6e-3 at the same setting: vertex differences are the noisiest here, the box's
    edges over the floor moving a little); the control: the gradient along another direction."""
    s, name = textured_floor(), "objects.floor.vertices"
    d = directional(s, random_direction(s, [name], rel=0.02), weights)
    assert d.masked < 0.05
    g = backward_masked(s, weights, d)
    assert d.error(g) <= 1e-2
    other = random_direction(s, [name], seed=4, rel=0.02)[name]
    assert abs((g[name] * other).sum() - d.fd) > 0.2 * abs(d.fd)
