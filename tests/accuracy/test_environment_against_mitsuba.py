"""Environment lights against Mitsuba's ``direct`` integrator, converged, on the same files at 128 x 128:
scenes/envmap.xml (an envmap with a bright sun, turned and scaled: read by warprt from the file), the same
scene under Mitsuba's ``constant`` emitter (warprt: an environment light of that radiance), and the TOML twin
(scenes/sky.toml) against the XML file; with the wrong readings the comparisons must catch.

Both images are box-filtered pixel means (warprt: SPP stratified samples; Mitsuba: its stratified sampler,
MITSUBA_SPP samples, box filter), so they differ by Mitsuba's noise (its image against another seed's: SSIM
0.9989 with the envmap, 0.9995 under the constant sky, measured) and warprt's fixed directions and samples.
Measured: the envmap SSIM 0.9969, mean |difference| 0.5% of the mean (256 directions, 9 samples; SSIM 0.9982
at 576), the constant sky 0.9982 and 0.2% (576, 9).
"""

import re
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

import warprt
from reference import mitsuba_variant
from reference.compare import metrics
from reference.mitsuba_direct import DirectRenderer

pytestmark = [pytest.mark.accuracy, pytest.mark.slow]

SCENES = Path(__file__).resolve().parents[2] / "scenes"
SCENE = SCENES / "envmap.xml"
SSIM_MIN = 0.995
MEAN_REL_MAX = 0.02  # mean |warprt - Mitsuba| over Mitsuba's mean, both clamped as metrics() clamps
MITSUBA_SPP = 4096
SKY = (0.8, 0.9, 1.0)  # the constant emitter's radiance


@pytest.fixture(scope="module")
def mi():
    mitsuba_variant()
    import mitsuba

    return mitsuba


def mitsuba_direct(path) -> np.ndarray:
    return DirectRenderer(path, sampler="stratified")(MITSUBA_SPP, seed=0, samples_per_pass=1024)


def mean_rel(ours, theirs) -> float:
    a, b = np.clip(ours, 0.0, 1.0), np.clip(theirs, 0.0, 1.0)
    return float(np.abs(a - b).mean() / b.mean())


def render(scene, light_samples: int, spp: int, spread: bool = False, **kw) -> np.ndarray:
    scene = scene.with_render(light_samples=light_samples, spp=spp, light_spread=spread)
    return warprt.render(scene, **kw).image.astype(np.float64)


def with_environment(scene, **changes):
    (i,) = [i for i, light in enumerate(scene.lights) if light.environment]
    lights = list(scene.lights)
    lights[i] = replace(lights[i], **changes)
    return replace(scene, lights=lights)


def agrees(ours, theirs, what: str) -> bool:
    ssim, rel = metrics(ours, theirs)[0], mean_rel(ours, theirs)
    print(f"{what}: SSIM {ssim:.4f}, mean |diff| {rel:.4f} of the mean")
    return ssim >= SSIM_MIN and rel <= MEAN_REL_MAX


# ---- the envmap ----

@pytest.fixture(scope="module")
def envmap(mi):
    return warprt.load_scene(SCENE), mitsuba_direct(SCENE)


def test_the_envmap_scene_is_mitsubas_direct_render(envmap):
    scene, theirs = envmap
    assert agrees(render(scene, 256, 9), theirs, "envmap, 256 directions, 9 spp")


def test_the_envmap_spread_over_the_pixel_samples_is_mitsubas_direct_render(envmap):
    """render.light_spread: each of the 16 pixel samples takes 64 of the 1,024 directions, a sixteenth of the
    shadow rays of every sample taking them all (measured: SSIM 0.9988, mean |diff| 0.26%)."""
    scene, theirs = envmap
    assert agrees(render(scene, 1024, 16, spread=True), theirs, "envmap, 1024 directions spread over 16 spp")


def test_the_envmap_turned_the_other_way_fails(envmap):
    scene, theirs = envmap
    light = scene.environment
    turned = with_environment(scene, rotate=tuple(-a for a in light.rotate))
    assert not agrees(render(turned, 256, 9), theirs, "to_world's rotation inverted")


def test_the_envmap_without_shadows_fails(envmap):
    scene, theirs = envmap
    assert not agrees(render(scene, 256, 9, disable=("shadows",)), theirs, "no shadow rays")


# ---- the envmap as a USD DomeLight ----

def usd_dome(folder, turn: float):
    """scenes/envmap.xml's envmap as USD has it: a DomeLight of the same image (UsdLux's OpenEXR latlong layout),
    intensity 0.8 (the envmap's scale), turned ``turn`` degrees about +y, read by warprt's USD reader (its light
    alone: the stage's one triangle is there because a mesh file must have one)."""
    from pxr import Usd, UsdGeom, UsdLux

    path = folder / f"dome_{turn:+.0f}.usda"
    stage = Usd.Stage.CreateNew(str(path))
    UsdGeom.SetStageUpAxis(stage, "Y")
    mesh = UsdGeom.Mesh.Define(stage, "/World/Tri")
    mesh.CreatePointsAttr([(0, 0, 0), (1, 0, 0), (0, 1, 0)])
    mesh.CreateFaceVertexCountsAttr([3])
    mesh.CreateFaceVertexIndicesAttr([0, 1, 2])
    dome = UsdLux.DomeLight.Define(stage, "/World/Sky")
    dome.CreateIntensityAttr(0.8)
    dome.CreateTextureFileAttr(str(SCENES / "textures" / "sky.hdr"))
    UsdGeom.Xformable(dome).AddRotateYOp().Set(turn)
    stage.GetRootLayer().Save()
    (light,) = warprt.scene.read_mesh_file(path).lights
    return light


def with_light(scene, light):
    return replace(scene, lights=[light if l.environment else l for l in scene.lights])


def test_a_usd_dome_light_of_the_envmap_is_mitsubas_direct_render(envmap, tmp_path):
    """The envmap scene lit by a USD DomeLight of its image, turned 60 degrees about +y as the file's to_world
    turns its envmap, against Mitsuba's render of the XML file (measured: SSIM 0.9969, as the XML's own
    envmap); the control, the dome turned the other way, fails."""
    scene, theirs = envmap
    assert agrees(render(with_light(scene, usd_dome(tmp_path, 60.0)), 256, 9), theirs, "USD dome, 256 directions")
    assert not agrees(render(with_light(scene, usd_dome(tmp_path, -60.0)), 256, 9), theirs, "USD dome turned back")


# ---- the constant sky ----

@pytest.fixture(scope="module")
def constant_sky(mi, tmp_path_factory):
    """Mitsuba's direct render of the envmap scene with a constant emitter of radiance SKY in its place, and
    warprt's reading of the same file (the constant an environment light of radiance SKY)."""
    text = re.sub(r'<emitter type="envmap">.*?</emitter>',
                  f'<emitter type="constant"><rgb name="radiance" value="{", ".join(map(str, SKY))}"/></emitter>',
                  SCENE.read_text(), flags=re.S)
    path = tmp_path_factory.mktemp("constant") / "constant.xml"
    path.write_text(text)
    scene = warprt.load_scene(path)
    return scene, mitsuba_direct(path)


def test_a_constant_environment_is_mitsubas_constant_emitter(constant_sky):
    scene, theirs = constant_sky
    (sky,) = scene.lights
    assert sky.type == "environment" and np.allclose(sky.radiance, SKY, rtol=1e-6)
    assert scene.render.ambient == (0.0, 0.0, 0.0)
    assert agrees(render(scene, 576, 9), theirs, "constant sky, 576 directions, 9 spp")


def test_a_constant_sky_as_an_unoccluded_ambient_term_fails(constant_sky):
    """The negative control: the sky read as the XML reader reads a constant emitter (ambient pi L, seen
    everywhere, no shadows) is not Mitsuba's occluded sky light."""
    scene, theirs = constant_sky
    ambient = replace(scene, lights=[], render=replace(scene.render, ambient=tuple(np.pi * np.asarray(SKY)),
                                                       background=SKY))
    assert not agrees(render(ambient, 16, 9), theirs, "the constant emitter as ambient light")


# ---- the TOML twin ----

@pytest.fixture(scope="module")
def xml_image(mi):
    return render(warprt.load_scene(SCENE), 64, 1)


def twin_agrees(ours, theirs) -> bool:
    """The same image but for the sphere's tessellation (the twin's 64 x 128 uv_sphere, the file's sphere at
    128 x 256): a few pixels of its silhouette and shading (measured: 0.11% off by more than 1e-3, SSIM 0.99997;
    1 pixel with the file's tessellation)."""
    ssim, off = metrics(ours, theirs)[0], float((np.abs(ours - theirs) > 1e-3).mean())
    print(f"twin: SSIM {ssim:.6f}, share of pixels off by more than 1e-3 {off:.5f}")
    return ssim >= 0.9999 and off <= 2e-3


def test_the_toml_twin_renders_as_the_xml_file(xml_image):
    assert twin_agrees(render(warprt.load_scene(SCENES / "sky.toml"), 64, 1), xml_image)


def test_the_toml_twin_turned_the_other_way_fails(xml_image):
    twin = warprt.load_scene(SCENES / "sky.toml")
    assert not twin_agrees(render(with_environment(twin, rotate=(0.0, -60.0, 0.0)), 64, 1), xml_image)


def test_the_xml_readers_texels_are_mitsubas(mi):
    """The file's envmap as warprt reads it from Mitsuba's loaded emitter and as warprt's own HDR reader reads
    textures/sky.hdr: the same texels, so either file gives the same light."""
    xml, toml = warprt.load_scene(SCENE).environment, warprt.load_scene(SCENES / "sky.toml").environment
    assert np.array_equal(xml.image.image, toml.image.image) and xml.image.image.max() == 150.0
    assert toml.scale == pytest.approx(xml.scale) and np.allclose(toml.rotate, xml.rotate, atol=1e-5)


def _environment_image(path) -> np.ndarray:
    """The texels warprt reads from an image file as an environment light's, row 0 at the top."""
    scene = warprt.load_dict({"lights": [{"type": "environment", "image": str(path)}], "objects": [{"shape": "plane"}]})
    return scene.environment.image.image[::-1]


def test_a_run_length_encoded_hdr_reads_as_mitsuba_reads_it(mi, tmp_path):
    """Mitsuba writes a Radiance file run-length encoded (scenes/textures/sky.hdr is flat): warprt's reader
    gives Mitsuba's own reading of it, texel for texel; the same image upside down does not."""
    image = np.random.default_rng(3).random((12, 40, 3)).astype(np.float32) * np.float32(20.0)
    image[:, 5:30] = 1.5  # runs
    mi.Bitmap(image).write(str(tmp_path / "sky.hdr"))
    mi.Bitmap(np.ascontiguousarray(image[::-1])).write(str(tmp_path / "flipped.hdr"))
    theirs = np.asarray(mi.Bitmap(str(tmp_path / "sky.hdr")), np.float32)
    assert (tmp_path / "sky.hdr").stat().st_size < image.size * 4 // 3  # run-length encoded: under 4 bytes a texel
    assert np.array_equal(_environment_image(tmp_path / "sky.hdr"), theirs)
    assert not np.allclose(_environment_image(tmp_path / "flipped.hdr"), theirs, rtol=0.1)


ANGLES = (20.0, 60.0, -30.0)  # about x, then y, then z


@pytest.fixture(scope="module")
def random_sky(mi, tmp_path_factory):
    """A random 16 x 8 sky (EXR), its envmap turned by ANGLES in a Mitsuba file, that file read by warprt, and
    Mitsuba's own emitter of it."""
    folder = tmp_path_factory.mktemp("random_sky")
    image = np.random.default_rng(5).random((8, 16, 3)).astype(np.float32) * np.float32(3.0)
    mi.Bitmap(image).write(str(folder / "random.exr"))
    rotations = "".join(f'<rotate {axis}="1" angle="{a}"/>' for axis, a in zip("xyz", ANGLES))
    (folder / "sky.xml").write_text(f"""<scene version="3.0.0">
        <sensor type="perspective"><float name="fov" value="150"/><string name="fov_axis" value="y"/>
            <transform name="to_world"><lookat origin="0, 0, 0" target="0.3, 0.2, -1" up="0, 1, 0"/></transform>
            <film type="hdrfilm"><integer name="width" value="48"/><integer name="height" value="32"/></film>
        </sensor>
        <emitter type="envmap"><string name="filename" value="random.exr"/><float name="scale" value="1.5"/>
            <transform name="to_world">{rotations}</transform></emitter>
        <shape type="sphere"><point name="center" value="0, -50, 0"/><float name="radius" value="0.01"/></shape>
    </scene>""")
    emitter = next(iter(mi.load_file(str(folder / "sky.xml")).emitters()))
    return warprt.load_scene(folder / "sky.xml"), emitter


def test_the_xml_envmaps_rotation_is_read_as_rotate_angles(random_sky):
    assert np.allclose(random_sky[0].environment.rotate, ANGLES, atol=1e-4)


def test_camera_rays_that_meet_nothing_see_mitsubas_envmap_eval(mi, random_sky):
    """Each pixel's centre ray (tests/oracle/camera.py) handed to Mitsuba's own envmap eval: warprt's image is it
    to float32 rounding (bilinear texels, the half-texel shift, the poles, the rotation, the scale); turned the
    other way it is not."""
    from oracle.camera import camera_rays

    scene, emitter = random_sky
    _, directions = camera_rays(scene.camera)

    d = -directions.reshape(-1, 3)
    si = mi.SurfaceInteraction3f()
    si.wi = mi.Vector3f(*(mi.Float(np.ascontiguousarray(d[:, k], np.float32)) for k in range(3)))
    theirs = np.asarray(emitter.eval(si), np.float64).reshape(3, -1).T.reshape(directions.shape)
    ours = warprt.render(scene).image.astype(np.float64)
    assert np.allclose(ours, theirs, rtol=1e-4, atol=1e-5)
    turned = with_environment(scene, rotate=tuple(-a for a in ANGLES))
    assert not np.allclose(warprt.render(turned).image, theirs, rtol=0.05)


def test_the_whitted_reference_refuses_an_environment_in_one_line(mi):
    """warprt compare's reference has no environment light: it says so rather than compare another image."""
    from reference import compare

    with pytest.raises(warprt.SceneError, match=r"lights: an environment light is not in the Whitted reference") as e:
        compare(warprt.load_scene(SCENES / "sky.toml"))
    assert "\n" not in str(e.value)


def test_mitsubas_envmap_is_the_openexr_latlong_layout_a_usd_dome_quotes(mi, tmp_path):
    """Why a DomeLight's texture is read as an envmap's, unturned (usd.py): Mitsuba's envmap of an image painted
    at the OpenEXR latlong directions UsdLux quotes (test_dome_light.sky_image: c + b.d, 128 x 64) evaluates to
    c + b.d at random directions, to within the half texel between the two layouts' column centres (measured:
    0.012 at most, |b| pi / W = 0.020); the image's longitudes mirrored are 0.61 off."""
    from lighting.test_dome_light import B, C, sky_image, write_exr

    d = np.random.default_rng(7).normal(size=(2000, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    si = mi.SurfaceInteraction3f()
    si.wi = mi.Vector3f(*(mi.Float(np.ascontiguousarray(-d[:, k], np.float32)) for k in range(3)))
    errors = []
    for mirrored in (False, True):
        write_exr(tmp_path / "sky.exr", sky_image("Y", mirrored))
        emitter = mi.load_dict({"type": "envmap", "filename": str(tmp_path / "sky.exr")})
        theirs = np.asarray(emitter.eval(si), np.float64)[0]
        errors.append(float(np.abs(theirs - (C + d @ B)).max()))
    print(f"Mitsuba's envmap against c + b.d: {errors[0]:.4f}, mirrored {errors[1]:.4f}")
    assert errors[0] < 0.02 and errors[1] > 0.3
