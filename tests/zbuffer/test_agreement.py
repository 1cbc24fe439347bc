"""The Z-buffer against the ray tracer with shadows, reflections and glass off, on every scene: two
independent visibility algorithms (screen-space edge functions in float64 against Warp's watertight
float32 ray-triangle test in a BVH) must see the same triangle, and then one shading function must
give the same image.

Samples whose visible triangle may legitimately differ are ties, decided in float64 by
tests/zbuffer/compare.py, independently of both renderers:
- on an edge shared by two triangles, or a crease where two surfaces meet: Warp's test counts the
  sample in both and keeps whichever its BVH reaches first; the rasterizer's top-left rule gives it
  to exactly one.
- on a silhouette edge: one renderer sees the front triangle, the other what lies behind it.
- where two triangles overlap at equal depth (coplanar): each renderer has its own tie-break.
Measured: none in most scenes. Which triangle the tracer keeps at a tie depends on the order its
BVH meets the two: with one build of the BVH while it was being reworked, scenes/cornell.toml (its
centred camera and square image put pixel centres exactly on the projected corners of the box, the
image diagonals) had 112 ties of 25,600 samples at 160x160 and 332 of 313,600 at 560x560, a raw
agreement of 99.56 % and 99.89 % and a raw SSIM of 0.990 and 0.998; with the BVH at the time of
writing the tracer picks as the rasterizer does there, and scenes/tilted.toml has 2 ties of 921,600
samples at 640x360x4. At a tie
both colours are right, so ties count as agreement, tie pixels are taken from the tracer before SSIM,
and ties must stay on lines (< 1 % of samples).
Sensitivity, measured: shifting the rasterizer's projection by 1/50 pixel drops the agreement on
the default scene to 99.66 %, and by 1/500 pixel on the dense spheres to 99.72 %; clipping at
z = -near instead of at the eye drops it to 50 % on the eye-plane scene.
"""

from pathlib import Path

import pytest

import warprt
from marks import quick_cases
from tests.scenekit import make_scene
from tests.zbuffer.compare import compare

ROOT = Path(__file__).resolve().parents[2]
SCENES = sorted((ROOT / "scenes").glob("*.toml"))
WIDTH = 160  # small images keep the suite fast; scene files keep their aspect ratio

MATERIALS = {"wall": {"kd": [0.6, 0.5, 0.3], "ks": [0.3, 0.3, 0.3], "shininess": 20.0},
             "floor": {"kd": [0.3, 0.5, 0.6], "ks": [0.2, 0.2, 0.2]},
             "shiny": {"kd": [0.7, 0.2, 0.2], "ks": [0.8, 0.8, 0.8], "shininess": 90.0}}
LIGHTS = [{"position": [2.0, 3.0, 4.0]}, {"position": [-3.0, 1.0, 6.0], "color": [0.3, 0.3, 0.3]}]

# Seen from the eye at (0, 0, 5) looking down -z. The wall (x = -0.6) has one vertex behind the eye:
# clipped, it becomes a quad, and it reaches the eye, well inside the image plane at d_f = near = 2.
WALL = {"name": "wall", "shape": "triangles", "vertices": [[-0.6, -2.0, 9.0], [-0.6, -2.0, -4.0], [-0.6, 3.0, -1.0]],
        "faces": [[0, 1, 2]], "material": "wall"}
# The floor triangle has two vertices behind the eye: clipped, it stays a triangle.
FLOOR = {"name": "floor", "shape": "triangles", "vertices": [[-4.0, -0.8, 8.0], [4.0, -0.8, 8.0], [0.5, -0.8, -6.0]],
         "faces": [[0, 1, 2]], "material": "floor"}
BALL = {"shape": "sphere", "radius": 0.7, "subdivisions": 3, "smooth": True, "material": "shiny", "translate": [0.5, 0.0, 2.5]}


def eye_plane_scene(**camera):
    return make_scene([WALL, FLOOR, BALL], MATERIALS, LIGHTS, camera={"width": 96, "height": 64, "near": 2.0, **camera},
                      ambient=[0.1, 0.1, 0.1], background=[0.05, 0.05, 0.1])


def built_in_cases():
    default = warprt.load_scene().with_camera(width=WIDTH, height=120)
    dense = make_scene([{"shape": "sphere", "radius": 1.0, "subdivisions": 6, "smooth": True, "material": "shiny"},
                        {"shape": "sphere", "radius": 1.0, "subdivisions": 6, "material": "wall", "translate": [1.2, -0.3, -1.5]}],
                       MATERIALS, LIGHTS, camera={"eye": [0.3, 0.4, 2.6], "width": 128, "height": 96, "fovy": 50.0},
                       ambient=[0.1, 0.1, 0.1])
    return {
        "default": default,
        "default-spp4": default.with_camera(width=80, height=60).with_render(spp=4),
        # Geometry between the eye and the image plane: the tracer draws it, so must the Z-buffer.
        "default-near4": default.with_camera(near=4.0),
        # Non-square, camera low and tilted up, an up vector off the vertical.
        "tilted-nonsquare": default.with_camera(eye=(1.0, 0.4, 4.0), center=(-0.5, 1.6, 0.0), up=(0.3, 1.0, 0.2),
                                                 width=90, height=150),
        "eye-plane": eye_plane_scene(),
        "eye-plane-tilted": eye_plane_scene(eye=[0.2, -0.5, 5.0], center=[-0.6, 0.8, 0.0], up=[0.2, 1.0, 0.0],
                                            width=72, height=100),
        # 2 x 81,920 triangles of a few pixels each: samples on shared edges and vertices everywhere.
        "dense-spheres": dense,
        "empty": make_scene([], camera={"width": 32, "height": 24}, background=[0.2, 0.3, 0.4]),
    }


def scene_file_case(path: Path):
    scene = warprt.load_scene(path)
    height = max(8, round(WIDTH * scene.camera.height / scene.camera.width))
    return scene.with_camera(width=WIDTH, height=height)


CASES = list(built_in_cases()) + [f"scenes/{p.name}" for p in SCENES]
QUICK_CASES = quick_cases(CASES, {"eye-plane", "scenes/cornell.toml"})  # every case in the full suite, two in the quick loop


@pytest.fixture(scope="module")
def comparisons():
    built = built_in_cases()
    cache = {}

    def get(name):
        if name not in cache:
            scene = built[name] if name in built else scene_file_case(ROOT / name)
            cache[name] = compare(scene)
        return cache[name]

    return get


@pytest.mark.parametrize("name", QUICK_CASES)
def test_same_image_as_tracer_without_shadows_and_reflections(comparisons, name):
    c = comparisons(name)
    assert c.ssim >= 0.999, f"{name}: SSIM {c.ssim:.5f} (as rendered, ties included: {c.ssim_raw:.5f})"


@pytest.mark.parametrize("name", QUICK_CASES)
def test_same_visible_triangle_as_tracer(comparisons, name):
    c = comparisons(name)
    assert c.agreement >= 0.999, (f"{name}: visible triangle differs at {c.disagree - c.ties} of {c.samples} samples "
                                  f"that are not ties ({c.ties} ties)")


@pytest.mark.parametrize("name", QUICK_CASES)
def test_ties_lie_on_lines_only(comparisons, name):
    c = comparisons(name)
    assert c.ties <= 0.01 * c.samples, f"{name}: {c.ties} of {c.samples} samples are ties"


@pytest.mark.parametrize("name", QUICK_CASES)
def test_one_shading_function(comparisons, name):
    """Where both renderers see the same triangles, the colours agree to rounding: the same Phong
    function at the same point (only the barycentrics are computed differently)."""
    c = comparisons(name)
    assert c.max_diff_agreeing < 1e-3, f"{name}: colours differ by up to {c.max_diff_agreeing:.2e}"
