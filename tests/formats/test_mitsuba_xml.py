"""Mitsuba 3 scene files read through Mitsuba's own parser: what each sensor, shape, BSDF, texture and
emitter of a file the test writes becomes, against the numbers the test wrote (closed forms for the
camera's fov axes and the Fresnel reflectances), and the command line on good and bad files."""

import math
import os
import re
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

import mitsuba_files as mf
from warprt import SceneError, SceneWarning, load_scene
from warprt.scene import open_edges, read_mitsuba_xml, signed_volume, srgb_to_linear

mi = pytest.importorskip("mitsuba")
SRC = str(Path(__file__).resolve().parents[2] / "src")


@pytest.fixture(scope="module", autouse=True)
def variant():
    if mi.variant() is None:
        mi.set_variant("scalar_rgb")


def read(path):
    """The scene and the warnings its reading gave."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        scene = read_mitsuba_xml(path)
    return scene, [str(w.message) for w in caught if issubclass(w.category, SceneWarning)]


def transform(t, points):
    m = np.array(t.matrix, np.float64).reshape(4, 4)
    return np.asarray(points, np.float64) @ m[:3, :3].T + m[:3, 3]


def test_cornell_box_objects_are_its_shapes_where_mitsuba_puts_them(tmp_path):
    d = mf.cornell_box(mi)
    scene, warned = read(mf.write(tmp_path, "cornell.xml", d))
    names = ["light", "floor", "ceiling", "back", "green-wall", "red-wall", "small-box", "large-box"]
    assert [o.name for o in scene.objects] == names
    for o in scene.objects:
        shape = d[o.name]
        assert o.material == shape["bsdf"]["id"]
        unit = ([[x, y, 0] for x in (-1, 1) for y in (-1, 1)] if shape["type"] == "rectangle"
                else [[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)])
        corners = transform(shape["to_world"], unit)
        # The same corners (float32, as Mitsuba stores them), whatever their order.
        assert np.allclose(np.sort(np.unique(o.vertices.round(5), axis=0), 0), np.sort(corners.round(5), 0), atol=1e-5)
        assert len(o.faces) == (2 if shape["type"] == "rectangle" else 12)
    for name in ("white", "green", "red"):  # Mitsuba's diffuse BRDF is reflectance / pi
        assert np.allclose(scene.materials[name].kd, np.array(d[name]["reflectance"]["value"]) / math.pi, rtol=1e-6)
        assert scene.materials[name].ks == (0.0, 0.0, 0.0)
    point, area = scene.lights  # the Whitted lights first, then the area lights
    assert point.position == pytest.approx((0.0, 0.9, 0.0)) and point.falloff == "inverse_square"
    assert area.type == "area" and area.object == "light" and area.name == "light"
    assert area.radiance == pytest.approx(d["light"]["emitter"]["radiance"]["value"])
    assert scene.render.ambient == (0.0, 0.0, 0.0)
    assert not warned


def test_area_light_shines_from_the_side_mitsubas_emitter_does(tmp_path):
    """Mitsuba's area emitter lights the side its shape's normal faces, and flip_normals turns it (the
    buffers stay, the normals are negated at each hit): the triangles' winding faces that side."""
    d = mf.cornell_box(mi, point_light=None)
    d["flipped"] = {**d["light"], "flip_normals": True}
    scene, _ = read(mf.write(tmp_path, "cornell.xml", d))
    ms = mi.load_file(str(tmp_path / "cornell.xml"))
    by_name = {o.name: o for o in scene.objects}
    for shape in ms.shapes():
        if shape.is_emitter():
            # Mitsuba's own emitting side: the normal of a point it samples on the shape.
            side = np.array(shape.sample_position(0.0, [0.3, 0.4]).n, np.float64)
            o = by_name[shape.id()]
            v = o.vertices[o.faces]
            winding = np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0])
            assert (winding @ side > 0).all(), shape.id()
    assert [l.object for l in scene.lights] == ["light", "flipped"]
    assert (np.asarray(by_name["flipped"].faces) == np.asarray(by_name["light"].faces)[:, ::-1]).all()


def test_cornell_box_scene_file_is_mitsubas_box(tmp_path):
    """scenes/cornell_box.xml is mi.cornell_box() as Mitsuba writes it, at 64 x 64: read, the same scene."""
    ours = read_mitsuba_xml(Path(SRC).parent / "scenes" / "cornell_box.xml")
    theirs = read_mitsuba_xml(mf.write(tmp_path, "cornell.xml", mf.cornell_box(mi, 64, 64, point_light=None)))
    assert ours.camera == theirs.camera and ours.lights == theirs.lights and ours.materials == theirs.materials
    assert [o.name for o in ours.objects] == [o.name for o in theirs.objects]
    for a, b in zip(ours.objects, theirs.objects):
        assert np.array_equal(a.vertices, b.vertices) and np.array_equal(a.faces, b.faces)


@pytest.mark.parametrize("axis", ["x", "y", "diagonal", "smaller", "larger"])
def test_camera_fov_axis_becomes_the_vertical_fov(tmp_path, axis):
    w, h, fov = 80, 50, 50.0
    t = math.tan(math.radians(fov) / 2)
    # tan(fovy / 2) for each of Mitsuba's fov axes on a landscape film.
    expected = {"x": t * h / w, "y": t, "diagonal": t * h / math.hypot(w, h), "smaller": t, "larger": t * h / w}[axis]
    d = {"type": "scene", "sensor": mf.sensor(mi, (1.0, 2.0, 3.0), (0.0, 0.5, 0.0), up=(0.0, 1.0, 0.0), fov=fov,
                                              fov_axis=axis, width=w, height=h), "floor": mf.floor(mi)}
    cam = read(mf.write(tmp_path, "cam.xml", d))[0].camera
    assert math.tan(math.radians(cam.fovy) / 2) == pytest.approx(expected, rel=1e-6)
    assert (cam.width, cam.height) == (w, h)
    eye, forward = np.array([1.0, 2.0, 3.0]), np.array([-1.0, -1.5, -3.0]) / np.linalg.norm([1.0, 1.5, 3.0])
    assert np.allclose(cam.eye, eye, atol=1e-6)
    assert np.allclose(np.asarray(cam.center) - eye, forward, atol=1e-6)
    assert abs(np.dot(cam.up, forward)) < 1e-6 and np.cross(cam.up, forward)[1] == pytest.approx(0.0, abs=1e-6)


def test_defaults_params_includes_and_refs_mean_what_they_mean_in_mitsuba(tmp_path):
    (tmp_path / "materials.xml").write_text('<scene version="3.0.0"><bsdf type="diffuse" id="paint">'
                                            '<rgb name="reflectance" value="$r, 0.25, 0.125"/></bsdf></scene>')
    sensor = mf.to_xml({"type": "scene", "sensor": mf.sensor(mi, (0, 1, 3), (0, 0, 0))}).split("\n")[1:-2]
    (tmp_path / "scene.xml").write_text("\n".join([
        '<scene version="3.0.0">', '<default name="r" value="0.5"/>', '<default name="width" value="32"/>',
        *sensor, '<include filename="materials.xml"/>',
        '<shape type="rectangle" id="floor"><ref id="paint"/>'
        '<transform name="to_world"><rotate x="1" angle="-90"/><translate y="-0.5"/></transform></shape>', "</scene>"]))
    scene, _ = read(tmp_path / "scene.xml")
    assert np.allclose(scene.materials["paint"].kd, np.array([0.5, 0.25, 0.125]) / math.pi)
    assert np.allclose(scene.objects[0].vertices[:, 1], -0.5)
    assert read_mitsuba_xml(tmp_path / "scene.xml", {"r": 0.75}).materials["paint"].kd[0] == pytest.approx(0.75 / math.pi)


def fresnel_dielectric(eta):
    return ((eta - 1) / (eta + 1)) ** 2


def test_bsdfs_become_phong_materials_by_the_documented_rules(tmp_path):
    gold_eta, gold_k = np.array([0.2, 0.4, 1.4]), np.array([3.9, 2.4, 1.6])
    bsdfs = {
        "plastic": {"type": "plastic", "diffuse_reflectance": {"type": "rgb", "value": [0.6, 0.3, 0.3]}, "int_ior": 1.6},
        "rough": {"type": "roughplastic", "alpha": 0.2, "int_ior": 1.5},
        "gold": {"type": "conductor", "eta": {"type": "rgb", "value": list(gold_eta)},
                 "k": {"type": "rgb", "value": list(gold_k)}},
        "brushed": {"type": "roughconductor", "alpha": 0.3},
        "glass": {"type": "dielectric", "int_ior": 1.5, "ext_ior": 1.33},
        "sheet": {"type": "thindielectric", "int_ior": 1.5},
        "paper": {"type": "twosided", "b": {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.2, 0.4, 0.6]}}},
        "fancy": {"type": "principled"},
        "fancy2": {"type": "principled"},
    }
    d = {"type": "scene", "sensor": mf.sensor(mi, (0, 1, 3), (0, 0, 0)), **bsdfs}
    for i, name in enumerate(bsdfs):
        d[f"s{i}"] = {"type": "sphere", "center": [3.0 * i, 0.0, 0.0], "radius": 0.5, "bsdf": {"type": "ref", "id": name}}
    scene, warned = read(mf.write(tmp_path, "bsdfs.xml", d))
    m = scene.materials
    air = 1.000277  # Mitsuba's default ext_ior
    assert np.allclose(m["plastic"].kd, np.array([0.6, 0.3, 0.3]) / math.pi)
    assert np.allclose(m["plastic"].reflectivity, fresnel_dielectric(1.6 / air), rtol=1e-6)
    n = (2 / 0.2**2 - 2) / 4  # Blinn-Phong 2/alpha^2 - 2 as a Phong exponent
    assert m["rough"].shininess == pytest.approx(n)
    assert np.allclose(m["rough"].ks, fresnel_dielectric(1.5 / air) * (n + 2) / (2 * math.pi), rtol=1e-6)
    gold_f0 = ((gold_eta - 1) ** 2 + gold_k**2) / ((gold_eta + 1) ** 2 + gold_k**2)
    assert np.allclose(m["gold"].reflectivity, gold_f0, rtol=1e-5) and m["gold"].kd == (0.0, 0.0, 0.0)
    assert np.allclose(m["brushed"].reflectivity, 1.0)  # Mitsuba's default conductor: a perfect mirror
    assert m["glass"].ior == pytest.approx(1.5 / 1.33) and m["glass"].kd == (0.0, 0.0, 0.0)
    assert m["sheet"].ior == pytest.approx(1.5 / air, rel=1e-6)
    assert np.allclose(m["paper"].kd, np.array([0.2, 0.4, 0.6]) / math.pi)
    assert np.allclose(m["fancy"].kd, 0.5 / math.pi)
    principled = [w for w in warned if "principled" in w.lower()]
    assert len(principled) == 1, warned  # one warning for the kind, not one per shape
    assert len([w for w in warned if "thindielectric: rendered as a solid" in w]) == 1


def test_glass_sphere_is_a_closed_tessellation_of_mitsubas_sphere(tmp_path):
    scene, _ = read(mf.write(tmp_path, "glass.xml", mf.glass_sphere(mi)))
    glass = scene.objects[1]
    c, r = np.array(mf.GLASS["center"]), mf.GLASS["radius"]
    assert np.allclose(np.linalg.norm(glass.vertices - c, axis=1), r, rtol=1e-12)
    assert open_edges(glass.vertices, glass.faces) == 0
    rings = 128  # SPHERE_SEGMENTS: a chord's sagitta is at most r (1 - cos(pi / rings))
    volume = 4 / 3 * math.pi * r**3
    assert volume * (1 - 3 * (1 - math.cos(math.pi / rings))) < signed_volume(glass.vertices, glass.faces) < volume
    assert np.allclose(np.linalg.norm(glass.normals, axis=1), 1.0)
    assert scene.materials[glass.material].ior == pytest.approx(mf.GLASS["int_ior"] / mf.GLASS["ext_ior"])


def test_textures_are_mitsubas_texels_and_uv_maps(tmp_path):
    png = mf.checker_png(tmp_path / "t.png")
    scene, _ = read(mf.write(tmp_path, "plane.xml", mf.textured_plane(mi, png)))
    bitmap = scene.materials[scene.objects[0].material].kd_texture
    texels = srgb_to_linear(np.asarray(Image.open(png), np.float64) / 255.0)
    # Mitsuba's rows with Mitsuba's uv (row 0 at v = 0 in both); its to_uv scale 2.
    assert np.allclose(bitmap.image, texels, atol=1e-6)
    assert bitmap.uv_transform == (2.0, 0.0, 0.0, 0.0, 2.0, 0.0)
    checks = scene.materials[scene.objects[1].material].kd_texture
    assert np.allclose(checks.checker, [[0.9, 0.8, 0.1], [0.1, 0.2, 0.7]])
    assert checks.uv_transform == (6.0, 0.0, 0.0, 0.0, 6.0, 0.0)  # Mitsuba's half-unit checks: 2 x its scale 3


def test_spot_directional_and_constant_emitters(tmp_path):
    scene, _ = read(mf.write(tmp_path, "spot.xml", mf.spot_lit_floor(mi)))
    s = mf.SPOT
    spot, sun, sky = scene.lights
    axis = np.subtract(s["target"], s["origin"])
    assert spot.type == "spot" and spot.falloff == "inverse_square" and spot.name == "lamp"
    assert np.allclose(spot.position, s["origin"], atol=1e-6)
    assert np.allclose(spot.direction, axis / np.linalg.norm(axis), atol=1e-6)
    assert (spot.cutoff_angle, spot.beam_width) == pytest.approx((s["cutoff_angle"], s["beam_width"]))
    assert np.allclose(spot.color, s["intensity"])
    assert sun.type == "directional" and sun.position is None and sun.falloff == "none"
    assert np.allclose(sun.direction, np.divide(s["sun"], np.linalg.norm(s["sun"])), atol=1e-6)
    assert np.allclose(sun.color, s["irradiance"])
    # A constant sky L: an environment light of radiance L (its background and its occluded light), no ambient.
    assert sky.type == "environment" and sky.image is None and sky.name == "sky" and np.allclose(sky.radiance, s["sky"])
    assert scene.render.background == (0.0, 0.0, 0.0) and scene.render.ambient == (0.0, 0.0, 0.0)


def test_a_constant_beside_an_envmap_is_mitsubas_refusal_in_one_line(tmp_path):
    """Mitsuba takes one environment emitter a scene: a constant and an envmap together are its error."""
    import OpenEXR

    with OpenEXR.File({"type": OpenEXR.scanlineimage}, {"RGB": np.ones((4, 8, 3), np.float32)}) as f:
        f.write(str(tmp_path / "sky.exr"))
    mf.write(tmp_path, "two.xml", {**mf.spot_lit_floor(mi), "map": {"type": "envmap", "filename": str(tmp_path / "sky.exr")}})
    r = warprt_cli("render", "two.xml", "-o", "out.png", cwd=tmp_path)
    lines = r.stderr.strip().split("\n")
    assert r.returncode == 2 and len(lines) == 1
    assert lines[0].startswith("warprt: error: two.xml: Mitsuba rejects it: ") and "Only one environment emitter" in lines[0]


def warprt_cli(*args, cwd, env_extra=""):
    code = f"import sys; {env_extra}sys.argv = ['warprt', *{list(args)!r}]; from warprt.cli import run; run()"
    return subprocess.run([sys.executable, "-c", code], cwd=cwd, capture_output=True, text=True,
                          env={**os.environ, "PYTHONPATH": SRC}, timeout=600)


def test_render_and_info_of_a_scene_file(tmp_path):
    mf.write(tmp_path, "cornell.xml", mf.cornell_box(mi, width=24, height=18))
    r = warprt_cli("render", "cornell.xml", "-o", "c.png", "-q", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert Image.open(tmp_path / "c.png").size == (24, 18)
    r = warprt_cli("info", "cornell.xml", cwd=tmp_path)
    assert r.returncode == 0 and "small-box" in r.stdout and "lights     2" in r.stdout
    assert re.search(r"light\s+area\s+object 'light' radiance \[18.38", r.stdout), r.stdout
    assert "warning" not in r.stderr


@pytest.mark.parametrize("text, words", [
    ('<scene version="3.0.0"><shape type="sphere"><float name="radiusx" value="1"/></shape></scene>',
     'unreferenced property in shape plugin of type "sphere"'),
    ('<scene version="3.0.0"><shape type="teapot"/></scene>', 'Plugin "teapot" not found'),
    ('<scene version="3.0.0"><shape type="sphere"></scene>', "Start-end tags mismatch"),
    ('<scene version="3.0.0"><bsdf type="diffuse" id="a"/><shape type="sphere"><ref id="b"/></shape></scene>', '"b"'),
])
def test_a_file_mitsuba_rejects_is_its_message_in_one_line(tmp_path, text, words):
    (tmp_path / "bad.xml").write_text(text)
    r = warprt_cli("render", "bad.xml", "-o", "out.png", cwd=tmp_path)
    assert r.returncode == 2 and r.stdout == ""
    lines = r.stderr.strip().split("\n")
    assert len(lines) == 1 and lines[0].startswith("warprt: error: bad.xml: Mitsuba rejects it: ") and words in lines[0]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.xml"]


def test_nothing_warprt_can_render_is_exit_2(tmp_path):
    mf.write(tmp_path, "empty.xml", {"type": "scene", "sensor": mf.sensor(mi, (0, 1, 3), (0, 0, 0)),
                                     "sky": {"type": "constant"}})
    r = warprt_cli("render", "empty.xml", "-o", "out.png", cwd=tmp_path)
    assert r.returncode == 2
    assert r.stderr == "warprt: error: empty.xml: no shape warprt can render (meshes, rectangle, cube, sphere, disk, cylinder)\n"
    assert not (tmp_path / "out.png").exists()


def test_without_mitsuba_a_one_line_error(tmp_path):
    mf.write(tmp_path, "cornell.xml", mf.cornell_box(mi, width=8, height=6))
    r = warprt_cli("render", "cornell.xml", "-o", "c.png", cwd=tmp_path, env_extra="sys.modules['mitsuba'] = None; ")
    assert r.returncode == 2
    assert r.stderr.strip() == ("warprt: error: cornell.xml: reading a Mitsuba scene file needs Mitsuba 3 "
                                "(pip install 'warprt[mitsuba]'): import of mitsuba halted; None in sys.modules")
    assert not (tmp_path / "c.png").exists()


def test_load_scene_overrides_and_rejects_other_keys(tmp_path):
    path = mf.write(tmp_path, "cornell.xml", mf.cornell_box(mi))
    scene = load_scene(path, {"camera.width": 40, "render.spp": 4})
    assert scene.camera.width == 40 and scene.render.spp == 4
    with pytest.raises(SceneError, match="only camera.. and render.. can be set"):
        load_scene(path, {"lights[0].color": [1, 1, 1]})


@pytest.mark.parametrize("ext", ["obj", "ply"])
def test_mesh_files_are_placed_by_their_to_world(tmp_path, ext):
    import trimesh

    box = trimesh.creation.box(extents=[1.0, 2.0, 0.5])
    box.export(tmp_path / f"box.{ext}")
    to_world = mi.ScalarTransform4f().translate([0.5, -1.0, 2.0]) @ mi.ScalarTransform4f().rotate([0, 1, 0], 30.0)
    d = {"type": "scene", "sensor": mf.sensor(mi, (0, 1, 6), (0, 0, 0)),
         "box": {"type": ext, "filename": str(tmp_path / f"box.{ext}"), "to_world": to_world}}
    scene, warned = read(mf.write(tmp_path, "mesh.xml", d))
    (obj,) = scene.objects
    expected = transform(to_world, box.vertices)
    assert np.allclose(np.sort(np.unique(obj.vertices.round(5), axis=0), 0), np.sort(np.unique(expected.round(5), axis=0), 0), atol=1e-5)
    assert len(obj.faces) == 12 and not warned


def test_wrapped_bsdfs_are_read_through_with_one_warning_each(tmp_path):
    paint = {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.3, 0.6, 0.9]}}
    d = {"type": "scene", "sensor": mf.sensor(mi, (0, 1, 3), (0, 0, 0)),
         "masked": {"type": "mask", "opacity": 0.5, "b": paint},
         "bumped": {"type": "twosided", "b": {"type": "normalmap", "normalmap": {"type": "bitmap", "raw": True,
                    "filename": str(mf.checker_png(tmp_path / "n.png"))}, "b": paint}}}
    for i, name in enumerate(["masked", "bumped", "masked"]):
        d[f"s{i}"] = {"type": "sphere", "center": [3.0 * i, 0, 0], "bsdf": {"type": "ref", "id": name}}
    scene, warned = read(mf.write(tmp_path, "wrapped.xml", d))
    assert [o.material for o in scene.objects] == ["masked", "bumped", "masked"]
    for name in ("masked", "bumped"):
        assert np.allclose(scene.materials[name].kd, np.array([0.3, 0.6, 0.9]) / math.pi)
    assert len(warned) == 2 and "mask: its opacity" in warned[0] and "normalmap" in warned[1]


def test_area_emitters_and_environment_maps_are_lights_textured_radiance_one_warning(tmp_path):
    mi.Bitmap(np.ones((4, 8, 3), np.float32)).write(str(tmp_path / "sky.exr"))
    glow = {"type": "area", "radiance": {"type": "rgb", "value": [5.0, 4.0, 3.0]}}
    pattern = {"type": "area", "radiance": {"type": "checkerboard"}}
    d = {"type": "scene", "sensor": mf.sensor(mi, (0, 1, 3), (0, 0, 0)),
         "sky": {"type": "envmap", "filename": str(tmp_path / "sky.exr")},
         "a": {**mf.floor(mi), "emitter": glow}, "b": {**mf.floor(mi), "emitter": dict(glow)},
         "c": {**mf.floor(mi), "emitter": pattern}}
    scene, warned = read(mf.write(tmp_path, "glow.xml", d))
    assert [(l.type, l.object, l.radiance) for l in scene.lights] == [("environment", None, None),
                                                                       ("area", "a", (5.0, 4.0, 3.0)),
                                                                       ("area", "b", (5.0, 4.0, 3.0))]
    assert scene.environment.image.image.shape == (4, 8, 3) and np.all(scene.environment.image.image == 1.0)
    assert len(scene.objects) == 3
    assert len(warned) == 1 and "textured area emitter" in warned[0]
