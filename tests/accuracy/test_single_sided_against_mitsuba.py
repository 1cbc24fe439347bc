"""Single-sided glTF materials against the Mitsuba reference, which continues its rays past the same
back faces with Mitsuba's own intersection and spawn_ray: lit, seen from behind by camera, reflection
and refraction rays, every pixel as the accuracy suite checks it."""

import textwrap

import pytest

import warprt

from accuracy.harness import check
from formats.gltf_files import quaternion
from formats.test_single_sided import quad_gltf

pytestmark = pytest.mark.accuracy

SCENE = """
    [camera]
    eye = [{eye}]
    center = [0.0, 0.0, 0.0]
    fovy = 60.0
    width = 96
    height = 96
    [render]
    ambient = [0.1, 0.1, 0.1]
    max_depth = 3
    [[lights]]
    position = [{light}]
    color = [0.8, 0.8, 0.8]
    [materials.backdrop]
    kd = [0.2, 0.4, 0.7]
    ks = [0.3, 0.3, 0.3]
    shininess = 20.0
    [[objects]]
    mesh = "q.gltf"
    [[objects]]
    shape = "plane"
    size = [20.0, 20.0]
    rotate = [90.0, 0.0, 0.0]
    translate = [0.0, 0.0, {backdrop}]
    material = "backdrop"
    """

MIRROR = """
    [materials.mirror]
    kd = [0.05, 0.05, 0.05]
    reflectivity = 0.9
    [[objects]]
    shape = "plane"
    size = [3.0, 3.0]
    rotate = [90.0, 45.0, 0.0]
    material = "mirror"
    """

GLASS = """
    [materials.glass]
    kd = [0.0, 0.0, 0.0]
    ior = 1.5
    [[objects]]
    shape = "box"
    size = [1.2, 1.2, 0.6]
    translate = [0.3, 0.2, -1.2]
    material = "glass"
    """


def scene(tmp_path, eye, light, backdrop, extra="", **quad):
    quad_gltf(tmp_path / "q.gltf", **quad)
    text = textwrap.dedent(SCENE).format(eye=eye, light=light, backdrop=backdrop) + textwrap.dedent(extra)
    (tmp_path / "s.toml").write_text(text)
    return warprt.load_scene(tmp_path / "s.toml")


@pytest.mark.parametrize("double_sided", [False, True])
@pytest.mark.parametrize("side", ["front", "behind"])
def test_single_sided_quad_matches_mitsuba(tmp_path, side, double_sided):
    if side == "front":
        s = scene(tmp_path, "0.5, 0.5, 4.0", "1.0, 2.0, 5.0", -2.0, double_sided=double_sided)
    else:
        s = scene(tmp_path, "0.5, 0.5, -4.0", "1.0, 2.0, -5.0", 2.0, double_sided=double_sided)
    check(f"single_sided_{side}_{'double' if double_sided else 'single'}", s)


def test_mirror_sees_through_the_back_of_a_single_sided_quad_as_mitsuba_does(tmp_path):
    s = scene(tmp_path, "0.0, 0.3, 4.0", "2.0, 3.0, 3.0", -20.0, MIRROR + textwrap.dedent("""
        [[objects]]
        shape = "plane"
        size = [20.0, 20.0]
        rotate = [0.0, 0.0, 90.0]
        translate = [6.0, 0.0, 0.0]
        material = "backdrop"
        """), rotation=quaternion([0.0, 1.0, 0.0], 90.0), translation=[3.0, 0.0, 0.0])
    check("single_sided_mirror", s)


def test_refracted_rays_pass_the_back_of_a_single_sided_quad_as_in_mitsuba(tmp_path):
    """The glass block stands between the camera (behind the quad) and the quad: its refracted rays meet
    the quad's back (the ray tree of reference/ray_tree.py)."""
    s = scene(tmp_path, "0.5, 0.5, -4.0", "1.0, 2.0, -5.0", 2.0, GLASS)
    assert "C" in warprt.render(s).stats.variant.split("_")[1]  # the culling variant
    check("single_sided_glass", s)
