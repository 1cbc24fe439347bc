"""AOVs against closed forms: each camera sample's first hit traced in float64 by the oracle (its rays
from the seed's camera formula, Moller-Trumbore on the scene's own triangles), then averaged or picked
by the issue's rules, written here from the definitions: geometric AOVs averaged over the samples that
hit, IDs from the sample nearest the pixel centre, coverage the share that hit."""

import numpy as np
import pytest

import warprt
from scenekit import make_scene
from oracle import face_normals, nearest_triangle, ray_directions, ray_triangle, vertex_normals

# An oblique quad (the plane z = x/4 + y/4, two triangles) and a small triangle in front of it, each
# with its own material; the camera (scenekit's, on +z) sees background around the quad's corners.
QUAD = [[-3.0, -2.0, -1.25], [3.0, -2.0, 0.25], [3.0, 2.0, 1.25], [-3.0, 2.0, -0.25]]
TRI = [[-0.5, -0.5, 1.0], [0.8, -0.4, 1.2], [0.0, 0.7, 1.1]]
OBJECTS = [{"shape": "triangles", "vertices": QUAD, "faces": [[0, 1, 2], [0, 2, 3]], "material": "floor"},
           {"shape": "triangles", "vertices": TRI, "faces": [[0, 1, 2]], "material": "card"}]
MATERIALS = {"card": {"kd": [0.1, 0.6, 0.2]}, "floor": {"kd": [0.7, 0.5, 0.3]}}
TRIANGLES = np.array([np.array(QUAD)[[0, 1, 2]], np.array(QUAD)[[0, 2, 3]], np.array(TRI)])
OBJECT_OF = np.array([0, 0, 1])  # per triangle of TRIANGLES: its object, and its index within it
FACE_IN_OBJECT = np.array([0, 1, 0])
ALL = ("depth", "normal", "albedo", "position", "uv", "object", "material", "face", "coverage")
TOO_CLOSE = 1e-4  # a sample this near an edge (in barycentrics) is float32's to decide: left out


def scene_of(objects=OBJECTS, camera=None, **render):
    return make_scene(objects, MATERIALS, (), camera, ambient=[0.2, 0.2, 0.2], **render)


def sample_hits(scene, triangles, k: int):
    """For each of a pixel's k x k samples, sample j k + i at ((i + 1/2)/k, (j + 1/2)/k) from the
    pixel's lower left: the unit ray direction, the nearest triangle (-1: none), its distance, and the
    ray's distance to the nearest edge. Arrays (H, W, k*k, ...)."""
    cam = scene.camera
    rows, cols = np.meshgrid(np.arange(cam.height), np.arange(cam.width), indexing="ij")
    eye = np.asarray(cam.eye, np.float64)
    dirs, faces, ts, edges = [], [], [], []
    for j in range(k):
        for i in range(k):
            d = ray_directions(cam, cols, rows, (i + 0.5) / k, (j + 0.5) / k)
            d = d / np.linalg.norm(d, axis=-1, keepdims=True)
            t, f, edge = nearest_triangle(eye, d, triangles)
            dirs.append(d), faces.append(f), ts.append(t), edges.append(edge)
    return eye, np.stack(dirs, 2), np.stack(faces, 2), np.stack(ts, 2), np.stack(edges, 2)


def pixel_hits(scene, triangles):
    """sample_hits of one sample per pixel, at its centre: eye, and arrays (H, W, ...)."""
    eye, *per_sample = sample_hits(scene, triangles, 1)
    return (eye, *(x[:, :, 0] for x in per_sample))


def nearest_centre_sample(k: int) -> int:
    """The sample nearest the pixel centre, the first in sample order among equally near ones."""
    offsets = [((i + 0.5) / k - 0.5) ** 2 + ((j + 0.5) / k - 0.5) ** 2 for j in range(k) for i in range(k)]
    return int(np.argmin(offsets))  # argmin takes the first of equal values


def facing(n, d):
    """Normals n turned to face rays travelling along d."""
    return np.where((np.sum(n * d, -1) > 0)[..., None], -n, n)


def test_a_plane_depth_normal_position_uv_at_every_pixel():
    scene = scene_of()
    result = warprt.render(scene, aovs=list(ALL))
    a = result.aovs
    eye, d, f, t, edge = pixel_hits(scene, TRIANGLES)
    clear = (edge > TOO_CLOSE) & (f >= 0)
    assert clear.sum() > 0.5 * f.size  # the quad fills most of the view
    np.testing.assert_allclose(a["depth"][clear], t[clear], rtol=1e-5)
    p = eye + t[..., None] * d
    np.testing.assert_allclose(a["position"][clear], p[clear], rtol=0, atol=1e-5)
    n = facing(face_normals(TRIANGLES)[np.maximum(f, 0)], d)
    np.testing.assert_allclose(a["normal"][clear], n[clear], atol=1e-6)
    tri = TRIANGLES[np.maximum(f, 0)]
    h = ray_triangle(eye, d, tri[..., 0, :], tri[..., 1, :], tri[..., 2, :])  # u, v: the weights of b and c
    np.testing.assert_allclose(a["uv"][clear], np.stack([h.u, h.v], -1)[clear], atol=1e-5)
    assert np.isinf(a["depth"][f < 0]).all() and (f < 0).any()


def test_ids_albedo_and_coverage_at_one_sample_per_pixel():
    scene = scene_of()
    a = warprt.render(scene, aovs=list(ALL)).aovs
    _, _, f, _, edge = pixel_hits(scene, TRIANGLES)
    clear = edge > TOO_CLOSE
    material_index = {name: list(scene.materials).index(name) for name in MATERIALS}  # "default" is 0
    obj = np.where(f >= 0, OBJECT_OF[f], -1)
    assert np.array_equal(a["object"][clear], obj[clear])
    assert np.array_equal(a["face"][clear], np.where(f >= 0, FACE_IN_OBJECT[f], -1)[clear])
    material = np.where(obj == 1, material_index["card"], np.where(obj == 0, material_index["floor"], -1))
    assert np.array_equal(a["material"][clear], material[clear])
    kd = {0: MATERIALS["floor"]["kd"], 1: MATERIALS["card"]["kd"], -1: [0.0, 0.0, 0.0]}
    np.testing.assert_array_equal(a["albedo"][clear], np.float32([kd[o] for o in obj[clear]]))
    assert np.array_equal(a["coverage"][clear], (f >= 0)[clear].astype(np.float32))
    assert set(np.unique(obj[clear])) == {-1, 0, 1}


@pytest.mark.parametrize("k", [2, 3])
def test_geometric_aovs_average_the_samples_that_hit_and_ids_come_from_the_centre_sample(k):
    """k = 2: four samples equally near the centre, the first (lower left) decides; k = 3: the middle one."""
    scene = scene_of(spp=k * k)
    a = warprt.render(scene, aovs=list(ALL)).aovs
    eye, d, f, t, edge = sample_hits(scene, TRIANGLES, k)
    clear = (edge > TOO_CLOSE).all(-1)
    hit = f >= 0
    n_hit = hit.sum(-1)
    mixed = clear & (n_hit > 0) & ((n_hit < k * k) | (f != f[..., :1]).any(-1))
    assert mixed.sum() >= 10  # pixels on the quad's border and the triangle's edges
    assert np.array_equal(a["coverage"][clear], (n_hit / (k * k)).astype(np.float32)[clear])
    mean = lambda x: np.sum(np.where(hit[..., None], x, 0.0), 2) / np.maximum(n_hit, 1)[..., None]
    some = clear & (n_hit > 0)
    np.testing.assert_allclose(a["depth"][some], mean(t[..., None])[..., 0][some], rtol=1e-5)
    np.testing.assert_allclose(a["position"][some], mean(eye + t[..., None] * d)[some], atol=1e-5)
    n = facing(face_normals(TRIANGLES)[np.maximum(f, 0)], d)
    np.testing.assert_allclose(a["normal"][some], mean(n)[some], atol=1e-6)
    centre = f[..., nearest_centre_sample(k)]
    assert np.array_equal(a["object"][clear], np.where(centre >= 0, OBJECT_OF[centre], -1)[clear])
    assert np.array_equal(a["face"][clear], np.where(centre >= 0, FACE_IN_OBJECT[centre], -1)[clear])
    # Never averaged: every ID is one of the objects or -1, also where the samples disagree.
    assert set(np.unique(a["object"][mixed])) <= {-1, 0, 1}


# The card with texture coordinates and vertex colours; the quad with a checker texture on its own uv.
UV = [[0.1, 0.2], [0.9, 0.3], [0.4, 0.8]]
COLORS = [[1.0, 0.2, 0.2], [0.2, 1.0, 0.2], [0.2, 0.2, 1.0]]
QUAD_UV = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]
CHECKS = [[0.9, 0.8, 0.7], [0.1, 0.2, 0.3]]


def attributes_scene():
    quad = {**OBJECTS[0], "uv": QUAD_UV, "material": "checked"}
    card = {**OBJECTS[1], "uv": UV, "colors": COLORS}
    materials = {**MATERIALS, "checked": {"kd": [0.5, 1.0, 1.0], "kd_texture": {"checker": CHECKS, "scale": 4}}}
    return make_scene([quad, card], materials, (), None, ambient=[0.2, 0.2, 0.2])


def test_uv_is_the_texture_coordinates_and_albedo_the_textured_and_coloured_kd():
    """uv: each object's texture coordinates interpolated at the hit; albedo: kd times the checker's
    colour there (4 x 4 checks over the quad's unit uv square) or times the interpolated vertex colour."""
    scene = attributes_scene()
    a = warprt.render(scene, aovs=["uv", "albedo", "object"]).aovs
    eye, d, f, t, edge = pixel_hits(scene, TRIANGLES)
    tri = TRIANGLES[np.maximum(f, 0)]
    h = ray_triangle(eye, d, tri[..., 0, :], tri[..., 1, :], tri[..., 2, :])
    weights = np.stack([1.0 - h.u - h.v, h.u, h.v], -1)  # of the triangle's corners a, b, c
    corners = {0: np.array(QUAD_UV)[[0, 1, 2]], 1: np.array(QUAD_UV)[[0, 2, 3]], 2: np.array(UV)}
    uv = np.einsum("...k,...kj->...j", weights, np.array([corners[i] for i in range(3)])[np.maximum(f, 0)])
    checks = np.floor(4.0 * uv)
    on_a_check = np.all(np.abs(4.0 * uv - np.rint(4.0 * uv)) > 1e-3, -1)  # not on a check's border
    clear = (edge > TOO_CLOSE) & (f >= 0) & on_a_check
    np.testing.assert_allclose(a["uv"][clear], uv[clear], atol=1e-5)
    colour = np.einsum("...k,kj->...j", weights, np.array(COLORS))
    check = np.where((checks.sum(-1) % 2 == 0)[..., None], CHECKS[0], CHECKS[1])
    albedo = np.where((f == 2)[..., None], np.array(MATERIALS["card"]["kd"]) * colour, np.array([0.5, 1.0, 1.0]) * check)
    np.testing.assert_allclose(a["albedo"][clear], albedo[clear], atol=1e-5)
    assert len(np.unique(check[clear & (f < 2)], axis=0)) == 2  # both checks seen


def test_smooth_shading_normal_is_the_interpolated_vertex_normal():
    sphere = {"shape": "sphere", "radius": 1.5, "subdivisions": 2, "smooth": True, "material": "floor"}
    scene = scene_of([sphere])
    a = warprt.render(scene, aovs=["normal", "uv", "face"]).aovs
    obj = scene.objects[0]
    tris = obj.vertices[obj.faces]
    eye, d, f, t, edge = pixel_hits(scene, tris)
    clear = (edge > TOO_CLOSE) & (f >= 0)
    assert clear.sum() > 300
    assert np.array_equal(a["face"][clear], f[clear])
    hit = tris[np.maximum(f, 0)]
    b1, b2 = ray_triangle(eye, d, hit[..., 0, :], hit[..., 1, :], hit[..., 2, :])[1:3]
    vn = vertex_normals(obj.vertices, obj.faces)[obj.faces[np.maximum(f, 0)]]  # (H, W, 3 corners, 3)
    n = (1 - b1 - b2)[..., None] * vn[..., 0, :] + b1[..., None] * vn[..., 1, :] + b2[..., None] * vn[..., 2, :]
    n = facing(n / np.linalg.norm(n, axis=-1, keepdims=True), d)
    np.testing.assert_allclose(a["normal"][clear], n[clear], atol=1e-5)
    flat = facing(face_normals(tris)[np.maximum(f, 0)], d)
    assert np.abs(a["normal"][clear] - flat[clear]).max() > 0.05  # shading, not geometric, normals


def test_position_far_from_the_origin_keeps_the_precision_near_the_eye():
    """The scene and camera moved by 1e5: a float32 world coordinate there is 0.0078 apart from the
    next; the AOV's float64 reconstruction from the eye-relative hit stays within 1e-5."""
    shift = np.array([1e5, -1e5, 1e5])
    moved = [{**o, "vertices": (np.array(o["vertices"]) + shift).tolist()} for o in OBJECTS]
    scene = scene_of(moved, camera={"eye": (np.array([0.0, 0.0, 5.0]) + shift).tolist(), "center": shift.tolist()})
    a = warprt.render(scene, aovs=["position", "depth"]).aovs
    eye, d, f, t, edge = pixel_hits(scene, TRIANGLES + shift)
    clear = (edge > TOO_CLOSE) & (f >= 0)
    assert a["position"].dtype == np.float64
    error = np.abs(a["position"][clear] - (eye + t[..., None] * d)[clear]).max()
    assert error < 1e-5 < np.spacing(np.float32(1e5))


def test_misses_hold_the_documented_values():
    scene = scene_of(camera={"center": [0.0, 10.0, 0.0], "eye": [0.0, 10.0, 5.0]})  # looking past everything
    result = warprt.render(scene, aovs=list(ALL))
    a = result.aovs
    assert np.isinf(a["depth"]).all() and (a["depth"] > 0).all()
    for name in ("normal", "albedo", "position", "uv", "coverage"):
        assert not a[name].any(), name
    for name in ("object", "material", "face"):
        assert (a[name] == -1).all(), name


def test_shapes_and_types():
    scene = scene_of(camera={"width": 20, "height": 10})
    a = warprt.render(scene, aovs=list(ALL)).aovs
    shapes = {n: (v.shape, v.dtype) for n, v in a.items()}
    f32, i32 = np.dtype(np.float32), np.dtype(np.int32)
    assert shapes == {"depth": ((10, 20), f32), "normal": ((10, 20, 3), f32), "albedo": ((10, 20, 3), f32),
                      "position": ((10, 20, 3), np.dtype(np.float64)), "uv": ((10, 20, 2), f32),
                      "object": ((10, 20), i32), "material": ((10, 20), i32), "face": ((10, 20), i32),
                      "coverage": ((10, 20), f32)}


def test_the_image_and_ray_counts_are_the_same_with_aovs():
    scene = warprt.load_scene().with_camera(width=40, height=30)
    image, stats = warprt.render(scene)
    result = warprt.render(scene, aovs=list(ALL))
    image_aov, stats_aov = result  # still a pair
    assert np.array_equal(image, image_aov) and stats.rays == stats_aov.rays
    assert stats_aov.variant == stats.variant + "_aov_" + "_".join(ALL)
    assert stats_aov.memory["aovs"] > 0 == stats.memory["aovs"]
    assert result.aovs.keys() == set(ALL) and warprt.render(scene).aovs == {}


def test_traced_and_hybrid_first_hits_give_the_same_aovs():
    scene = scene_of(spp=4)
    traced = warprt.render(scene, aovs=list(ALL), primary_query="raytrace")
    hybrid = warprt.render(scene, aovs=list(ALL), primary_query="zbuffer")
    assert hybrid.stats.primary_query == "zbuffer"
    for name in ALL:
        assert np.array_equal(traced.aovs[name], hybrid.aovs[name]), name


def test_object_tables_are_built_only_for_the_id_aovs():
    from warprt.geometry import Geometry

    scene = scene_of(camera={"width": 8, "height": 6})
    geometry = Geometry(scene)
    warprt.render(scene, aovs=["depth", "coverage"], geometry=geometry)
    assert geometry.object_ids is None
    before = warprt.render(scene, geometry=geometry).stats.memory["geometry"]["per_triangle"]
    warprt.render(scene, aovs=["face"], geometry=geometry)
    assert geometry.object_ids is not None
    assert warprt.render(scene, geometry=geometry).stats.memory["geometry"]["per_triangle"] == before + 4 * 3 + 4 * 2


@pytest.mark.parametrize("aovs, message", [
    (["depht"], "unknown AOV 'depht'"),
    (["depth", "depth"], "named twice"),
    ("depth", "expected a list of AOV names"),
])
def test_bad_aov_names_are_scene_errors(aovs, message):
    with pytest.raises(warprt.SceneError, match=message) as e:
        warprt.render(scene_of(camera={"width": 4, "height": 3}), aovs=aovs)
    assert e.value.field == "aovs"


def test_aovs_need_the_tracer():
    with pytest.raises(warprt.SceneError, match="not with algorithm='zbuffer'"):
        warprt.render(scene_of(camera={"width": 4, "height": 3}), aovs=["depth"], algorithm="zbuffer")
