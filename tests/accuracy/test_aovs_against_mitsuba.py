"""warprt's AOVs against Mitsuba 3's own ``aov`` integrator (reference/aov.py: depth, shading and
geometric normals, position, uv, shape and primitive index) on every scene of the accuracy suite.

Thresholds. Both renderers find hits in float32, Mitsuba in world coordinates, so its rounding grows
with |eye| + t, warprt relative to the eye; a ray-triangle hit is good to some tens of float32 ulps
(2^-24 = 6e-8) of that scale, more where a ray grazes its surface. Depth, position and uv (as the point
it names on the face: barycentrics, or texture coordinates where the object has them) may differ by
POSITION_REL (|eye|_max + depth), about 170 ulps; measured at the suite's width: at most 3.9e-6
(mirrors: a floor seen at a grazing angle). Normals: the same face gives
the same flat normal to float32 rounding (1e-7 rad); smooth normals are interpolated at hit points that
differ by the above, so they turn by the curvature times that: at most 6.4e-5 rad measured (the knot's
small triangles), NORMAL_ANGLE is 5e-4 rad. Indices must agree exactly wherever both hit, and hit or
miss must agree, except on a sample whose hit is a tie for float32 (the oracle's decision margin below
the suite's TIE_MARGIN: a ray within rounding of an edge, two surfaces at one distance); measured: none.
"""

import numpy as np
import pytest

import warprt
from reference import render_mitsuba_aovs
from reference.mitsuba_whitted import Switches
from warprt.scene import resolve_effects

from accuracy.harness import ROOT, SCENES, TIE_MARGIN, small
from marks import quick_cases
from oracle import Whitted

pytestmark = pytest.mark.accuracy

POSITION_REL = 1e-5
NORMAL_ANGLE = 5e-4
AOVS = ["depth", "normal", "position", "uv", "object", "face", "coverage"]


def angle(a, b):
    """The angle between vectors, well-conditioned near 0 (arccos of a dot product is not)."""
    a, b = np.asarray(a, np.float64), np.asarray(b, np.float64)
    return np.arctan2(np.linalg.norm(np.cross(a, b), axis=-1), np.sum(a * b, -1))


def point_on_face(scene, obj, face, uv):
    """The point on each pixel's face that its uv names: (1 - b1 - b2) p0 + b1 p1 + b2 p2 for the
    barycentrics (b1, b2), which uv is on an object without texture coordinates, and which solve
    uv = (1 - b1 - b2) t0 + b1 t1 + b2 t2 on one with them (t: its corners' coordinates). NaN where
    the face's texture coordinates have no area (they name no one point)."""
    out = np.zeros(uv.shape[:-1] + (3,))
    for idx in np.argwhere(obj >= 0):
        o = scene.objects[obj[tuple(idx)]]
        corners = o.faces[face[tuple(idx)]]
        p0, p1, p2 = o.vertices[corners]
        b = np.asarray(uv[tuple(idx)], np.float64)
        if getattr(o, "uv", None) is not None:
            t0, t1, t2 = np.asarray(o.uv, np.float64)[corners]
            m = np.column_stack([t1 - t0, t2 - t0])
            if abs(np.linalg.det(m)) < 1e-12:
                out[tuple(idx)] = np.nan
                continue
            b = np.linalg.solve(m, b - t0)
        out[tuple(idx)] = (1.0 - b[0] - b[1]) * p0 + b[0] * p1 + b[1] * p2
    return out


def facing_camera(scene, m):
    """Mitsuba's normals are the surface's; warprt's face the camera: turned by the geometric side, as
    the reference's integrator turns them. Smooth objects' pixels take the shading normal."""
    eye = np.asarray(scene.camera.eye, np.float64)
    side = np.where(np.sum(m["geo_normal"] * (m["position"] - eye), -1) > 0, -1.0, 1.0)[..., None]
    smooth = np.array([o.smooth for o in scene.objects]) & resolve_effects(scene).smooth
    on_smooth = m["hit"] & smooth[np.maximum(m["object"], 0)]
    return np.where(on_smooth[..., None], m["sh_normal"], m["geo_normal"]) * side, on_smooth


def unexplained(scene, pixels) -> list:
    """Of these (row, col) pixels, those whose camera ray's first hit is not a tie for float32."""
    oracle = Whitted(scene, Switches(diffuse=False, specular=False, shadows=False, max_depth=1, spp=1,
                                     smooth=resolve_effects(scene).smooth))
    return [(r, c) for r, c in pixels if oracle.pixel(c, r, "mitsuba").margin >= TIE_MARGIN]


def errors(scene, a, m, where):
    """Per pixel of ``where``: depth, position and uv-point differences over |eye|_max + depth, and the
    normal's angle."""
    scale = np.abs(np.asarray(scene.camera.eye)).max() + m["depth"]
    normal, _ = facing_camera(scene, m)
    uv_gap = np.abs(point_on_face(scene, m["object"], m["face"], a["uv"].astype(np.float64))
                    - point_on_face(scene, m["object"], m["face"], m["uv"])).max(-1)
    return {"depth": (np.abs(a["depth"] - m["depth"]) / scale)[where],
            "position": (np.abs(a["position"] - m["position"]).max(-1) / scale)[where],
            "uv": np.nan_to_num(uv_gap / scale)[where],
            "normal": angle(a["normal"], normal)[where]}


@pytest.mark.parametrize("path", quick_cases(SCENES, {"cornell", "tilted"}, [p.stem for p in SCENES]))
def test_scene_aovs_match_mitsubas_aov_integrator(path):
    scene = small(path, **{"render.spp": 1})
    a = warprt.render(scene, aovs=AOVS).aovs
    m = render_mitsuba_aovs(scene)
    hit = np.isfinite(a["depth"])
    assert np.array_equal(hit, a["coverage"] == 1.0) and hit.any()
    both = hit & m["hit"]
    differ = (hit != m["hit"]) | (both & ((a["object"] != m["object"]) | (a["face"] != m["face"])))
    bad = unexplained(scene, np.argwhere(differ))
    assert not bad, f"{len(bad)} pixels hit another surface than Mitsuba's, not at a tie: {bad[:10]}"
    same = both & ~differ
    assert same.sum() > 0.3 * same.size
    e = errors(scene, a, m, same)
    for name in ("depth", "position", "uv"):
        assert e[name].max() <= POSITION_REL, (name, e[name].max())
    assert e["normal"].max() <= NORMAL_ANGLE, e["normal"].max()


def test_supersampled_aovs_match_mitsuba_inside_objects():
    """2x2 samples: Mitsuba's film averages every sample (a miss as 0), warprt's geometric AOVs the
    samples that hit; inside an object, where all four hit it, they are the same mean."""
    scene = small(ROOT / "scenes" / "seed.toml", **{"render.spp": 4})
    a = warprt.render(scene, aovs=AOVS).aovs
    m = render_mitsuba_aovs(scene, spp=4)
    obj = np.pad(a["object"], 1, constant_values=-1)
    h, w = a["object"].shape
    uniform = np.all([obj[1 + dr:1 + dr + h, 1 + dc:1 + dc + w] == a["object"] for dr in (-1, 0, 1) for dc in (-1, 0, 1)], 0)
    inside = uniform & (a["coverage"] == 1.0)
    assert inside.sum() > 0.3 * inside.size
    assert np.array_equal(a["object"][inside], m["object"][inside])
    scale = np.abs(np.asarray(scene.camera.eye)).max() + m["depth"]
    assert (np.abs(a["depth"] - m["depth"]) / scale)[inside].max() <= POSITION_REL
    assert (np.abs(a["position"] - m["position"]).max(-1) / scale)[inside].max() <= POSITION_REL
    normal, _ = facing_camera(scene, m)
    assert angle(a["normal"], normal)[inside].max() <= NORMAL_ANGLE


def test_the_thresholds_catch_wrong_aovs():
    """The negative control: depth along the view axis instead of along the ray, the geometric normal
    instead of the shading one on a smooth object, and uv as Warp's own (b0, b1) each fail; a pixel well
    inside an object is no tie, so another hit there would not be explained away."""
    scene = small(ROOT / "scenes" / "curved_shadows.toml", **{"render.spp": 1})
    a = warprt.render(scene, aovs=AOVS).aovs
    m = render_mitsuba_aovs(scene)
    same = np.isfinite(a["depth"]) & m["hit"] & (a["object"] == m["object"]) & (a["face"] == m["face"])
    eye = np.asarray(scene.camera.eye, np.float64)
    forward = np.asarray(scene.camera.center, np.float64) - eye
    z_depth = (a["position"] - eye) @ (forward / np.linalg.norm(forward))
    b1, b2 = a["uv"][..., 0], a["uv"][..., 1]
    _, on_smooth = facing_camera(scene, m)
    wrong = {"depth": {**a, "depth": z_depth}, "uv": {**a, "uv": np.stack([1.0 - b1 - b2, b1], -1)},
             "normal": {**a, "normal": m["geo_normal"] * np.sign(np.sum(m["geo_normal"] * a["normal"], -1))[..., None]}}
    assert errors(scene, wrong["depth"], m, same)["depth"].max() > 10 * POSITION_REL
    assert errors(scene, wrong["uv"], m, same)["uv"].max() > 10 * POSITION_REL
    assert errors(scene, wrong["normal"], m, same & on_smooth)["normal"].max() > 10 * NORMAL_ANGLE
    row, col = (int(x) for x in np.argwhere(same)[len(np.argwhere(same)) // 2])
    assert unexplained(scene, [(row, col)]) == [(row, col)]
