"""Glass in both renderers against float64 closed forms (tests/oracle/optics.py), so that agreeing with
the Mitsuba ray tree means something: Mitsuba's own Fresnel and Snell against the formulas, then per
pixel the glass slab at incidence angles from 0 to 80 degrees, total internal reflection in the prism,
Beer's law through the cube, the view from inside glass, and the energy a clear object keeps."""

import math
import tomllib
from pathlib import Path

import numpy as np
import pytest

import warprt
from marks import quick_cases
from oracle import OFFSET_SWEEP, Whitted
from oracle import optics
from oracle import camera_rays
from reference import MitsubaScene, Switches, render_tree
from reference.mitsuba_whitted import mitsuba
from warprt.scene import resolve_effects, rotation, scene_from_dict

pytestmark = pytest.mark.accuracy

SCENES = Path(__file__).resolve().parents[2] / "scenes"


def edited(name: str, width: int, edit=None):
    """scenes/<name>.toml at ``width`` pixels across (its aspect kept), its parsed document changed by
    ``edit`` first (objects removed, settings no --set can reach)."""
    path = SCENES / f"{name}.toml"
    doc = tomllib.loads(path.read_text())
    cam = doc["camera"]
    cam["width"], cam["height"] = width, max(7, round(width * cam["height"] / cam["width"]))
    if edit is not None:
        edit(doc)
    return scene_from_dict(doc, str(path), path.parent)


def both(scene, effects=None):
    """(warprt's image, its truncated weights, Mitsuba's TreeResult) for the scene's effect set."""
    r = warprt.render(scene, effects=effects, report_truncated=True)
    switches = Switches.for_effects(resolve_effects(scene, effects), scene.render)
    tree = render_tree(MitsubaScene(scene, switches.smooth), switches)
    return r.image, r.stats.truncated, tree


def test_mitsubas_fresnel_and_snell_are_the_closed_forms_from_both_sides():
    mi, dr = mitsuba()
    c = np.linspace(-1.0, 1.0, 20001).astype(np.float32).astype(np.float64)
    for eta in (1.0001, 1.33, 1.5, 2.42, 0.75):
        F = np.array(mi.fresnel(mi.Float(c.astype(np.float32)), mi.Float(eta))[0])
        expect = np.where(c >= 0, optics.fresnel(c, 1.0, eta), optics.fresnel(c, eta, 1.0))
        cos_t2 = 1.0 - np.where(c >= 0, 1.0 / eta, eta) ** 2 * (1.0 - c**2)
        assert np.abs(F - expect)[np.abs(cos_t2) > 1e-2].max() < 5e-6  # float32 cancels near the critical angle
        assert (F[cos_t2 < 0] == 1.0).all()
    rng = np.random.default_rng(1)
    n = rng.normal(size=(4000, 3))
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    d = rng.normal(size=(4000, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    wi = mi.Vector3f(np.ascontiguousarray((-d).T.astype(np.float32)))
    F, cos_t, _, eta_ti = mi.fresnel(dr.dot(wi, mi.Normal3f(np.ascontiguousarray(n.T.astype(np.float32)))), mi.Float(1.5))
    t = np.array(mi.refract(wi, mi.Normal3f(np.ascontiguousarray(n.T.astype(np.float32))), cos_t, eta_ti)).T
    F = np.array(F)
    for i in range(len(d)):
        expect, _, _ = optics.refract_dir(d[i], n[i], 1.5)
        if expect is None:
            assert F[i] == 1.0
        else:
            assert np.linalg.norm(t[i] - expect) < 1e-5


# --- the slab: incidence from 0 to 80 degrees ------------------------------------------------------------

def slab_faces():
    """The faces of scenes/glass_slab.toml's slab (0.25 thick, turned 35 degrees about y, at z = -2)."""
    a = math.radians(35.0)
    n, u, v = np.array([math.sin(a), 0, math.cos(a)]), np.array([math.cos(a), 0, -math.sin(a)]), np.array([0.0, 1, 0])
    c, h, s = np.array([0.0, 0, -2]), 0.125, 20.0
    quad = lambda cc, uu: [cc - s * uu - s * v, cc + s * uu - s * v, cc + s * uu + s * v, cc - s * uu + s * v]
    return optics.Face(quad(c + h * n, u), n), optics.Face(quad(c - h * n, -u), -n)


def slab_closed_form(scene, glass):
    """Per pixel: red = the sum over paths leaving through the back of weight x the stripe they land
    on (ka 1 or 0.25, 1 wide, at z = -30), blue = 0.5 x the sum of the paths leaving through the front;
    every path plane_paths follows, as many internal reflections as max_depth allows. And which pixels
    are clear of the faces' and stripes' edges (1e-3)."""
    front, back = slab_faces()
    eye, dirs = camera_rays(scene.camera)
    depth = scene.render.max_depth
    H, W = dirs.shape[:2]
    d = dirs.reshape(-1, 3)
    out, clear = np.zeros((H * W, 3)), np.ones(H * W, bool)
    through = [[(front, "T")] + [(back, "R"), (front, "R")] * k + [(back, "T")] for k in range(depth) if 3 + 2 * k <= depth]
    back_out = ([[(front, "R")]] if depth >= 2 else []) + \
        [[(front, "T")] + [(back, "R"), (front, "R")] * k + [(back, "R"), (front, "T")] for k in range(depth) if 4 + 2 * k <= depth]
    for path in through + back_out:
        w, o, dd, margin, valid = optics.plane_paths(eye, d, path, glass.ior, glass.transmittance, glass.absorption)
        assert valid.all()  # no total internal reflection in a slab of parallel faces
        clear &= margin > 1e-3
        t = (-30.0 - o[:, 2]) / dd[:, 2]
        xl, yl = o[:, 0] + t * dd[:, 0], o[:, 1] + t * dd[:, 1]
        on = (t > 0) & (np.abs(xl) < 60) & (np.abs(yl) < 40)
        frac = xl - np.floor(xl)
        clear &= ~on | (np.minimum.reduce([frac, 1 - frac, 60 - np.abs(xl), 40 - np.abs(yl)]) > 1e-3)
        stripe = np.where(np.floor(xl + 60.0).astype(np.int64) % 2 == 0, 1.0, 0.25)
        out[:, 0] += np.where(on, w[:, 0] * stripe, 0.0)
        out[:, 2] += np.where(on, 0.0, 0.5 * w[:, 2])
    return out.reshape(H, W, 3), clear.reshape(H, W)


@pytest.mark.parametrize("max_depth", [3, 8])
def test_slab_at_every_incidence_angle_matches_the_closed_form(max_depth):
    """Light through a tilted slab: offset-parallel rays of weight (1-F)^2 k_t^2 exp(-sigma d / cos theta_t),
    plus the internal reflections max_depth allows; light back: F plus those that leave through the front."""
    scene = edited("glass_slab", 120, lambda doc: doc["render"].update(max_depth=max_depth))
    expect, clear = slab_closed_form(scene, scene.materials["glass"])
    assert clear.mean() > 0.98
    ours, _, tree = both(scene)
    # Both renderers start each refracted ray a little off the face (Mitsuba 1e-4 of the coordinates,
    # warprt its error bound, about 1e-4 for these 40-unit triangles), which shortens the segment
    # inside by up to that times sin^2/cos: up to 1e-4 of absorption at grazing incidence.
    for image in (ours, tree.image):
        assert np.abs(image - expect)[clear].max() < 1e-4


# --- the prism: total internal reflection ----------------------------------------------------------------

def test_prism_reflects_totally_past_the_critical_angle():
    """scenes/prism_tir.toml, ambient light only: seen through a leg, rays meet the hypotenuse inside at
    about 45 degrees; past asin(1/eta) = 41.8 degrees none gets through (no green from the panel behind),
    all go on to the other leg and the red panel; each pixel is the closed form's sum of the three paths."""
    def edit(doc):
        doc["render"].update(ambient=[1.0, 1.0, 1.0], background=[0.0, 0.0, 0.0], max_depth=4)

    scene = edited("prism_tir", 120, edit)
    glass = scene.materials["glass"]
    A = optics.Face([(-1, -3, 0), (1, -3, 0), (1, 3, 0), (-1, 3, 0)])  # the leg facing the eye
    Bf = optics.Face([(1, -3, 0), (1, -3, -2), (1, 3, -2), (1, 3, 0)])  # the other leg
    Hy = optics.Face([(-1, -3, 0), (-1, 3, 0), (1, 3, -2), (1, -3, -2)])  # the hypotenuse
    red = optics.Face([(3.95, -10, 8), (3.95, -10, -12), (3.95, 10, -12), (3.95, 10, 8)])
    green = optics.Face([(-30.1, -10, -5.95), (3.9, -10, -5.95), (3.9, 10, -5.95), (-30.1, 10, -5.95)])

    def panel(o, d):
        """The colour of the nearest panel each ray meets (black for none), and how far from an edge."""
        best, value, margin = np.full(len(d), np.inf), np.zeros((len(d), 3)), np.full(len(d), np.inf)
        for face, colour in ((red, (0.9, 0, 0)), (green, (0, 0.8, 0))):
            t, _, m = face.hit(o, d)
            ahead = np.isfinite(t) & (t > 1e-9)
            margin = np.where(ahead, np.minimum(margin, np.abs(m)), margin)
            nearer = ahead & (m > 0) & (t < best)
            best, value = np.where(nearer, t, best), np.where(nearer[:, None], colour, value)
        return value, margin

    eye, dirs = camera_rays(scene.camera)
    H, W = dirs.shape[:2]
    d = dirs.reshape(-1, 3)
    _, _, m_a = A.hit(np.broadcast_to(eye, d.shape), d)
    expect, margin = np.zeros((H * W, 3)), m_a.copy()
    for path in ([(A, "R")], [(A, "T"), (Hy, "T")], [(A, "T"), (Hy, "R"), (Bf, "T")]):
        w, o, dd, m, valid = optics.plane_paths(eye, d, path, glass.ior, glass.transmittance, glass.absorption)
        value, m_panel = panel(o, dd)
        expect += np.where(valid[:, None], w * value, 0.0)
        margin = np.minimum(margin, np.where(valid, np.minimum(m, m_panel), np.inf))
        if path[-1] == (Bf, "T"):
            margin = np.where(valid, margin, -1.0)  # total reflection at the second leg too: no closed form here
    _, _, inside, _, _ = optics.plane_paths(eye, d, [(A, "T")], glass.ior, glass.transmittance, glass.absorption)
    tir = (np.sqrt(1 - (inside @ Hy.n) ** 2) > 1.0 / glass.ior).reshape(H, W)
    expect, clear = expect.reshape(H, W, 3), ((m_a > 1e-3) & (margin > 1e-3)).reshape(H, W)
    assert clear.sum() > 3000 and (tir & clear).sum() > 2000 and (~tir & clear).sum() > 500
    ours, _, tree = both(scene, effects=["ambient", "refraction"])
    for image in (ours, tree.image):
        assert np.abs(image - expect)[clear].max() < 2e-5
        assert image[tir & clear][:, 1].max() == 0.0  # nothing through the hypotenuse


# --- the cube: Beer's law --------------------------------------------------------------------------------

def test_absorbing_cube_follows_beers_law_along_each_chord():
    """scenes/glass_cube.toml's cube alone before a background B, no local terms, 3 ray levels: a pixel
    is B (F_1 + (1 - F_1)(1 - F_2) exp(-sigma L)), F_1 where the ray enters, F_2 where its refracted ray
    meets the far face (1 past the critical angle), L the chord between them, found in the cube's frame."""
    background = np.array([0.6, 0.7, 0.8])

    def edit(doc):
        doc["objects"] = [o for o in doc["objects"] if o.get("name") == "cube"]
        doc["lights"] = []
        doc["render"].update(ambient=[0.0] * 3, background=background.tolist(), max_depth=3)

    scene = edited("glass_cube", 100, edit)
    glass = scene.materials["glass"]
    R, centre, half = rotation([20.0, 35.0, 0.0]), np.array([0.0, 1.2, 0.0]), 0.6
    eye, dirs = camera_rays(scene.camera)
    o = R.T @ (eye - centre)  # the eye in the cube's frame
    H, W = dirs.shape[:2]
    expect, clear = np.tile(background, (H, W, 1)), np.zeros((H, W), bool)
    sigma = np.asarray(glass.absorption)
    for row in range(H):
        for x in range(W):
            d = R.T @ dirs[row, x]
            with np.errstate(divide="ignore", invalid="ignore"):
                t0, t1 = (-half - o) / d, (half - o) / d
            near, far = np.minimum(t0, t1), np.maximum(t0, t1)
            t_in = near.max()
            if not t_in < far.min():
                clear[row, x] = abs(t_in - far.min()) > 1e-3  # a miss, away from the silhouette
                continue
            axis = int(np.argmax(near))
            p = o + t_in * d
            n = np.zeros(3)
            n[axis] = np.sign(p[axis])
            t, F1, _ = optics.refract_dir(d, n, glass.ior)
            with np.errstate(divide="ignore", invalid="ignore"):
                exits = np.where(t > 0, (half - p) / t, np.where(t < 0, (-half - p) / t, np.inf))
            L = exits.min()
            q = p + L * t
            exit_axis = int(np.argmin(exits))
            m = np.zeros(3)
            m[exit_axis] = np.sign(q[exit_axis])
            _, F2, _ = optics.refract_dir(t, m, glass.ior)
            edge = min(half - np.abs(np.delete(p, axis)).max(), half - np.abs(np.delete(q, exit_axis)).max())
            clear[row, x] = edge > 1e-3 and np.sort(exits)[1] - L > 1e-3
            expect[row, x] = background * (F1 + (1 - F1) * (1 - F2) * np.exp(-sigma * L))
    assert clear.sum() > 0.9 * H * W and (expect[clear] < background - 1e-3).any()
    ours, _, tree = both(scene)
    for image in (ours, tree.image):
        assert np.abs(image - expect)[clear].max() < 5e-5


# --- the view from inside ---------------------------------------------------------------------------------

def test_the_view_from_inside_glass_is_snells_window():
    """scenes/inside_glass.toml's box of water alone, the eye in it, 2 ray levels, background B: through
    a face under the critical angle asin(1/1.33) = 48.75 degrees a pixel is B (1 - F) k_t exp(-sigma t),
    t the distance to that face; past it the face reflects totally and the pixel is black."""
    background = np.array([0.3, 0.5, 0.8])

    def edit(doc):
        doc["objects"] = doc["objects"][:1]
        doc["render"].update(background=background.tolist(), max_depth=2)

    scene = edited("inside_glass", 100, edit)
    water = scene.materials["water"]
    eye, dirs = camera_rays(scene.camera)
    half = np.array([2.0, 1.5, 2.0])
    H, W = dirs.shape[:2]
    expect, clear, window = np.zeros((H, W, 3)), np.ones((H, W), bool), np.zeros((H, W), bool)
    for row in range(H):
        for x in range(W):
            d = dirs[row, x]
            ts = np.where(d > 0, (half - eye) / d, (-half - eye) / np.where(d == 0, 1, d))
            order = np.argsort(ts)
            t = ts[order[0]]
            clear[row, x] = ts[order[1]] - t > 1e-3 * t  # not at an edge of the box
            F = float(optics.fresnel(abs(d[order[0]]), water.ior, 1.0))
            window[row, x] = F < 1.0
            expect[row, x] = background * (1 - F) * np.asarray(water.transmittance) * np.exp(-np.asarray(water.absorption) * t)
    assert (window & clear).sum() > 1000 and (~window & clear).sum() > 1000
    ours, _, tree = both(scene)
    for image in (ours, tree.image):
        assert np.abs(image - expect)[clear].max() < 2e-5
        assert image[~window & clear].max() == 0.0


# --- energy ----------------------------------------------------------------------------------------------

@pytest.mark.parametrize("name", quick_cases(["glass_sphere", "prism_tir", "glass_cube", "inside_glass"], {"glass_cube"}))
def test_clear_glass_keeps_its_energy_and_both_cut_off_the_same_paths(name):
    """The scene's glass alone, clear (k_t 1, no absorption) and without local terms: in Mitsuba's tree
    what got out plus what max_depth cut off is 1 per pixel; warprt's truncated weight is Mitsuba's, and
    where it is not, the float64 oracle gives Mitsuba's value with Mitsuba's offsets and warprt's lies
    among its values for offsets from 2^-34 to 2^-14 of the coordinates (the truncated weight moves
    continuously with the offset: near the critical angle F changes fast, and an offset tilts every
    internal ray a little); both shrink as max_depth grows."""
    def edit(doc):
        key = next(k for k, m in doc["materials"].items() if "ior" in m)
        doc["objects"] = [o for o in doc["objects"] if o.get("material") == key]
        doc["materials"][key].update(absorption=0.0, transmittance=1.0, ks=[0.0] * 3)
        doc["lights"] = []
        doc["render"]["ambient"] = [0.0] * 3

    close = lambda a, b: np.abs(a - b).max() <= 1e-3 * max(np.abs(a).max(), np.abs(b).max()) + 2e-6
    means = []
    for depth in (2, 3, 5):  # one stack size: one kernel variant to compile
        scene = edited(name, 60, lambda doc: (edit(doc), doc["render"].update(max_depth=depth)))
        _, truncated, tree = both(scene)
        assert np.abs(tree.escaped + tree.truncated - 1.0).max() < 1e-5
        differ = np.argwhere((np.abs(truncated - tree.truncated) > 1e-4).any(-1))
        assert len(differ) <= 0.05 * truncated[..., 0].size, f"max_depth {depth}: {len(differ)} pixels differ"
        oracle = Whitted(scene, Switches.for_effects(resolve_effects(scene), scene.render))
        for row, x in differ:
            assert close(oracle.pixel(x, row, "mitsuba").truncated, tree.truncated[row, x]), (depth, row, x)
            swept = np.array([oracle.pixel(x, row, offset).truncated for offset in OFFSET_SWEEP])
            slack = 1e-3 * np.abs(swept).max() + 2e-6
            assert (swept.min(0) - slack <= truncated[row, x]).all() and (truncated[row, x] <= swept.max(0) + slack).all(), \
                (depth, row, x, truncated[row, x], swept)
        means.append((truncated.mean(), tree.truncated.mean()))
    assert means[0][0] > means[1][0] > means[2][0] and means[0][1] > means[1][1] > means[2][1]
