"""r.params: every parameter set between frames renders what a fresh load of a file saying the same
renders, to the bit (moved vertices: the same points, the BVH refit; ties that a refit tree breaks the
other way are counted); what a change leaves valid is kept; bad names and shapes are one SceneError."""

import copy

import numpy as np
import pytest
import warp as wp

import warprt
from marks import slow
from scenekit import write_scene
from warprt.image import write_image

TEXELS = np.random.default_rng(7).uniform(0.1, 0.9, (4, 6, 3)).astype(np.float32)  # row 0 at the top


def doc() -> dict:
    """A small scene with a parameter of every kind: image textures on kd (ka following it), on ka and ks,
    a mirror, absorbing glass, point, spot and directional lights."""
    return {
        "camera": {"eye": [0.3, 1.7, 5.0], "center": [0.0, 0.6, 0.0], "up": [0.0, 1.0, 0.0], "fovy": 50.0,
                   "near": 1.0, "width": 48, "height": 36},
        "render": {"ambient": [0.1, 0.1, 0.1], "background": [0.2, 0.3, 0.4], "max_depth": 4},
        "lights": [{"position": [-2.0, 5.0, 4.0], "color": [0.8, 0.8, 0.7]},
                   {"type": "spot", "position": [2.0, 4.0, 2.0], "direction": [-0.4, -1.0, -0.4],
                    "color": [0.5, 0.4, 0.3], "cutoff_angle": 40.0},
                   {"type": "directional", "direction": [0.3, -1.0, -0.2], "color": [0.2, 0.2, 0.25]}],
        "materials": {
            "floor": {"kd": [0.8, 0.8, 0.8], "kd_texture": "kd.exr", "ks": [0.1, 0.1, 0.1], "shininess": 8.0},
            "red": {"ka": [0.3, 0.1, 0.1], "ka_texture": "ka.exr", "kd": [0.7, 0.1, 0.1], "ks": [0.5, 0.5, 0.5],
                    "ks_texture": "ks.exr", "shininess": 32.0},
            "mirror": {"kd": [0.05, 0.05, 0.05], "reflectivity": [0.7, 0.7, 0.7]},
            "glass": {"ior": 1.5, "kd": [0.0, 0.0, 0.0], "ks": [0.6, 0.6, 0.6], "shininess": 200.0,
                      "transmittance": [0.9, 0.9, 0.9], "absorption": [0.2, 0.3, 0.1]},
        },
        "objects": [
            {"name": "floor", "shape": "plane", "size": [6.0, 6.0], "material": "floor"},
            {"name": "ball", "shape": "uv_sphere", "radius": 0.5, "segments": [8, 16], "smooth": True,
             "translate": [-0.8, 0.5, 0.3], "material": "red"},
            {"name": "block", "shape": "box", "size": [0.6, 0.6, 0.6], "translate": [0.7, 0.3, 0.6],
             "material": "glass"},
            {"name": "wall", "shape": "plane", "size": [3.0, 2.0], "rotate": [90.0, 0.0, 0.0],
             "translate": [0.0, 1.0, -1.5], "material": "mirror"},
        ],
    }


def load(folder, d: dict, name="scene.toml"):
    """The scene file ``d`` written to ``folder`` (with its textures) and read back."""
    for key in ("kd", "ka", "ks"):
        if not (folder / f"{key}.exr").exists():
            write_image(folder / f"{key}.exr", TEXELS * (1.0 if key == "kd" else 0.5))
    return warprt.load_scene(write_scene(folder, d, name))


def new_texture(folder, name: str, texels: np.ndarray) -> str:
    write_image(folder / name, texels)
    return name


# name -> (the value set through r.params, what the scene file says instead: fn(doc, folder) -> doc)
def _material(mat, key, value):
    return value, lambda d, f: (d["materials"][mat].__setitem__(key, value), d)[1]


def _light(i, key, value):
    return value, lambda d, f: (d["lights"][i].__setitem__(key, value), d)[1]


def _camera(key, value):
    return value, lambda d, f: (d["camera"].__setitem__(key, value), d)[1]


NEW_TEXELS = np.random.default_rng(8).uniform(0.0, 1.0, (3, 5, 3)).astype(np.float32)
CASES = {
    "materials.floor.kd": _material("floor", "kd", [0.3, 0.9, 0.4]),  # ka follows kd (and its texture)
    "materials.red.ka": _material("red", "ka", [0.05, 0.2, 0.1]),
    "materials.red.kd": _material("red", "kd", [0.1, 0.2, 0.9]),
    "materials.red.ks": _material("red", "ks", [0.9, 0.9, 0.2]),
    "materials.red.shininess": _material("red", "shininess", 5.0),
    "materials.mirror.reflectivity": _material("mirror", "reflectivity", [0.2, 0.5, 0.9]),
    "materials.glass.ior": _material("glass", "ior", 1.33),
    "materials.glass.transmittance": _material("glass", "transmittance", [0.5, 0.7, 0.9]),
    "materials.glass.absorption": _material("glass", "absorption", [0.9, 0.1, 0.4]),
    "materials.floor.kd_texture": (NEW_TEXELS, lambda d, f: (d["materials"]["floor"].__setitem__(
        "kd_texture", new_texture(f, "new.exr", NEW_TEXELS)), d)[1]),
    "materials.red.ka_texture": (NEW_TEXELS, lambda d, f: (d["materials"]["red"].__setitem__(
        "ka_texture", new_texture(f, "new.exr", NEW_TEXELS)), d)[1]),
    "materials.red.ks_texture": (NEW_TEXELS, lambda d, f: (d["materials"]["red"].__setitem__(
        "ks_texture", new_texture(f, "new.exr", NEW_TEXELS)), d)[1]),
    "lights.0.position": _light(0, "position", [1.0, 6.0, 1.0]),
    "lights.0.color": _light(0, "color", [0.2, 0.9, 0.3]),
    "lights.1.position": _light(1, "position", [-1.0, 3.0, 2.0]),
    "lights.1.direction": _light(1, "direction", [0.2, -1.0, -0.5]),
    "lights.2.direction": _light(2, "direction", [-0.5, -1.0, 0.1]),
    "lights.2.color": _light(2, "color", [0.5, 0.1, 0.1]),
    "camera.eye": _camera("eye", [-0.5, 2.0, 4.5]),
    "camera.center": _camera("center", [0.2, 0.4, -0.3]),
    "camera.up": _camera("up", [0.1, 1.0, 0.0]),
    "camera.fovy": _camera("fovy", 35.0),
}


def assert_same_frame(a, b):
    assert np.array_equal(a.image, b.image) and a.stats.rays == b.stats.rays


@pytest.mark.parametrize("name", list(CASES))
def test_a_parameter_set_renders_as_a_fresh_load_of_the_file_saying_it(tmp_path, name):
    value, edit = CASES[name]
    scene = load(tmp_path, doc())
    r = warprt.Renderer(scene, primary_query="raytrace")
    before = r.render()
    r.params[name] = value
    after = r.render()
    fresh_scene = load(tmp_path, edit(doc(), tmp_path), "edited.toml")
    fresh = warprt.render(fresh_scene, primary_query="raytrace")
    assert_same_frame(after, fresh)
    assert not np.array_equal(after.image, before.image)  # the change shows: the test could fail
    # Read back as the file's scene has it (a direction made unit, as every reader does).
    assert np.array_equal(r.params[name], warprt.Renderer(fresh_scene).params[name])


def test_every_name_of_the_module_table_is_covered(tmp_path):
    """The cases above name every kind the scene has (the vertices have their own tests below)."""
    names = set(warprt.Renderer(load(tmp_path, doc())).params)
    kinds = {n for n in names if not n.startswith("objects.")}
    assert {n.rsplit(".", 1)[1] for n in kinds} == {n.rsplit(".", 1)[1] for n in CASES}
    assert {n for n in names if n.startswith("objects.")} == {f"objects.{o}.{k}" for o in ("floor", "ball", "block", "wall")
                                                               for k in ("vertices", "translation", "rotation")}


def moved(vertices: np.ndarray) -> np.ndarray:
    """The ball's vertices squashed and moved: the objects' bounding box, and so the frame origin, move too."""
    return vertices * [1.0, 0.8, 1.0] + [2.5, 0.2, -0.4]


def test_moved_vertices_refit_the_bvh_and_render_as_a_fresh_load(tmp_path):
    d = doc()
    scene = load(tmp_path, d)
    r = warprt.Renderer(scene, primary_query="raytrace")
    r.render()
    mesh = r.geometry.mesh
    ball = r.params["objects.ball.vertices"]
    r.params["objects.ball.vertices"] = moved(ball)
    after = r.render()
    assert after.stats.geometry["bvh"] == "refit" and r.geometry.mesh is mesh
    # The file saying the same: the ball as explicit triangles at the moved vertices.
    faces = r.scene.objects[1].faces
    edited = copy.deepcopy(d)
    uv = r.scene.objects[1].uv
    edited["objects"][1] = {"name": "ball", "shape": "triangles", "vertices": moved(ball).tolist(),
                            "faces": faces.tolist(), "uv": uv.tolist(), "smooth": True, "material": "red"}
    fresh_scene = warprt.load_dict(edited, base=tmp_path)
    fresh = warprt.Renderer(fresh_scene, primary_query="raytrace")
    fresh_result = fresh.render()
    assert np.array_equal(r.geometry.points_np, fresh.geometry.points_np)
    assert np.array_equal(r.geometry.origin, fresh.geometry.origin)
    # The two trees hold the same padded boxes over the same points: every ray's nearest t is the same,
    # and only where two faces tie at that t may the trees return different ones.
    t_refit, face_refit = cast(r.geometry)
    t_fresh, face_fresh = cast(fresh.geometry)
    assert np.array_equal(t_refit, t_fresh) and np.isfinite(t_fresh).sum() > 20_000
    ties = int((face_refit != face_fresh).sum())
    differ = int(np.any(after.image != fresh_result.image, axis=-1).sum())
    print(f"of {len(t_fresh)} rays, {ties} tied faces returned differently; {differ} of "
          f"{after.image.shape[0] * after.image.shape[1]} pixels differ")
    assert ties <= 0.05 * len(t_fresh) and differ <= 0.01 * after.image.shape[0] * after.image.shape[1]


def cast(geom, n: int = 40_000):
    """Nearest t and face of ``n`` fixed rays on ``geom``'s BVH, with Warp's own closest-hit query: from
    points in and around the scene, half in any direction, half aimed at triangles' edge midpoints and
    vertices, where two faces meet at one t (the ties)."""
    rng = np.random.default_rng(3)
    lo, hi = geom.points_np.min(0), geom.points_np.max(0)
    origins = rng.uniform(lo - 1.0, hi + 1.0, (n, 3)).astype(np.float32)
    directions = rng.normal(size=(n, 3)).astype(np.float32)
    tri = geom.points_np[geom.indices_np.reshape(-1, 3)[: geom.triangle_count]]
    aims = np.concatenate([tri.reshape(-1, 3), (tri + np.roll(tri, 1, axis=1)).reshape(-1, 3) / 2])
    aimed = aims[rng.integers(0, len(aims), n // 2)]
    directions[: n // 2] = aimed - origins[: n // 2]
    t = wp.zeros(n, dtype=float, device="cpu")
    face = wp.zeros(n, dtype=int, device="cpu")
    wp.launch(_closest, dim=n, inputs=[geom.mesh.id, wp.array(origins, dtype=wp.vec3), wp.array(directions, dtype=wp.vec3),
                                       t, face], device="cpu")
    return t.numpy(), face.numpy()


@wp.kernel
def _closest(mesh: wp.uint64, origins: wp.array(dtype=wp.vec3), directions: wp.array(dtype=wp.vec3),
             t: wp.array(dtype=float), face: wp.array(dtype=int)):
    i = wp.tid()
    q = wp.mesh_query_ray(mesh, origins[i], wp.normalize(directions[i]), 1.0e6)
    t[i] = wp.where(q.result, q.t, wp.inf)
    face[i] = wp.where(q.result, q.face, -1)


def test_refit_is_a_negative_control_for_the_padding(tmp_path):
    """Refitting keeps the padded boxes: the refit BVH's bounds contain every moved triangle's box grown by
    the padding (a refit over the real triangles alone would hold only their exact boxes)."""
    scene = load(tmp_path, doc())
    r = warprt.Renderer(scene)
    r.render()
    r.params["objects.ball.vertices"] = moved(r.params["objects.ball.vertices"])
    r.render()
    g = r.geometry
    v, t = g.triangle_count and len(g.points_np), g.triangle_count
    corners = g.points.numpy()[v:]
    lower, upper = corners[:t], corners[t:2 * t]
    tri = g.points_np[g.indices_np.reshape(-1, 3)]
    assert np.all(lower < tri.min(axis=1)) and np.all(upper > tri.max(axis=1))


def test_several_parameters_at_once_and_the_caches_they_leave(tmp_path):
    scene = load(tmp_path, doc())
    r = warprt.Renderer(scene, shadow_query="grid", primary_query="raytrace")
    r.render()
    r.params.update({"materials.red.kd": [0.2, 0.8, 0.2], "camera.fovy": 40.0})
    stats = r.render().stats
    assert stats.geometry["bvh"] == "reused" and stats.shadow_grid["grid"] == "reused"  # lights unchanged
    r.params["lights.0.position"] = [0.0, 7.0, 0.0]
    assert r.render().stats.shadow_grid["grid"] == "built"  # a grid is for its lights
    r.params["objects.wall.vertices"] = r.params["objects.wall.vertices"] + [0.0, 0.0, -0.1]
    stats = r.render().stats
    assert stats.geometry["bvh"] == "refit" and stats.shadow_grid["grid"] == "built"  # the triangles moved


def coloured() -> dict:
    """doc() with vertex colours on a triangle object standing on the floor."""
    d = copy.deepcopy(doc())
    d["objects"].append({"name": "fan", "shape": "triangles", "material": "red",
                         "vertices": [[-1.5, 0.05, -0.5], [1.5, 0.05, -0.8], [0.0, 1.8, -1.0]], "faces": [[0, 1, 2]],
                         "colors": [[1.0, 0.1, 0.1], [0.1, 1.0, 0.1], [0.1, 0.1, 1.0]]})
    return d


NEW_COLORS = [[0.2, 0.9, 0.4], [0.7, 0.3, 0.1], [0.4, 0.5, 1.5]]


def test_vertex_colours_set_render_as_a_fresh_load_the_bvh_kept(tmp_path):
    """objects.<name>.colors, where an object has them: the colours written over the kept Geometry's (its BVH
    kept, not rebuilt), the frame a fresh load's to the bit; with its vertices at once, a rebuild, the same."""
    d = coloured()
    r = warprt.Renderer(load(tmp_path, d), primary_query="raytrace")
    before = r.render()
    mesh = r.geometry.mesh
    objects = ("floor", "ball", "block", "wall", "fan")
    assert [n for n in r.params if n.startswith("objects.")] == [f"objects.{o}.vertices" for o in objects] + [
        f"objects.{o}.{k}" for o in objects for k in ("translation", "rotation")] + ["objects.fan.colors"]
    r.params["objects.fan.colors"] = NEW_COLORS
    after = r.render()
    assert after.stats.geometry["bvh"] == "reused" and r.geometry.mesh is mesh
    edited = copy.deepcopy(d)
    edited["objects"][-1]["colors"] = NEW_COLORS
    fresh_scene = load(tmp_path, edited, "edited.toml")
    assert_same_frame(after, warprt.render(fresh_scene, primary_query="raytrace"))
    assert not np.array_equal(after.image, before.image)
    assert np.array_equal(r.params["objects.fan.colors"], warprt.Renderer(fresh_scene).params["objects.fan.colors"])
    moved = np.asarray(d["objects"][-1]["vertices"]) + [0.1, 0.0, 0.2]
    r.params.update({"objects.fan.colors": np.asarray(NEW_COLORS) * 0.5, "objects.fan.vertices": moved})
    edited["objects"][-1].update(colors=(np.asarray(NEW_COLORS) * 0.5).tolist(), vertices=moved.tolist())
    assert_same_frame(r.render(), warprt.render(load(tmp_path, edited, "moved.toml"), primary_query="raytrace"))
    with pytest.raises(warprt.SceneError, match="objects.fan.colors"):
        r.params["objects.fan.colors"] = [[0.1, 0.2, 0.3]]  # one colour per vertex
    with pytest.raises(warprt.SceneError, match="unknown parameter"):
        r.params["objects.ball.colors"] = np.ones((3, 3))  # the ball has none


@pytest.mark.parametrize("shape", ["rectangle", "sphere"])
def test_an_area_lights_centre_set_renders_as_a_fresh_load(tmp_path, shape):
    """lights.<i>.center of a shape light: its drawn triangles and its sample points move together, as a file
    saying the new centre gives them (the Geometry built again for the light's new triangles)."""
    d = copy.deepcopy(doc())
    light = {"type": "area", "shape": shape, "center": [0.5, 2.5, 0.5], "radiance": [3.0, 2.5, 2.0]}
    light.update({"normal": [0.0, -1.0, 0.3], "size": [0.8, 0.5]} if shape == "rectangle" else {"radius": 0.3})
    d["lights"] = [d["lights"][0], light]
    d["render"]["light_samples"] = 4
    r = warprt.Renderer(load(tmp_path, d), primary_query="raytrace")
    before = r.render()
    r.params["lights.1.center"] = [-0.4, 2.2, 0.9]
    after = r.render()
    edited = copy.deepcopy(d)
    edited["lights"][1]["center"] = [-0.4, 2.2, 0.9]
    fresh_scene = load(tmp_path, edited, "edited.toml")
    assert_same_frame(after, warprt.render(fresh_scene, primary_query="raytrace"))
    assert not np.array_equal(after.image, before.image)
    assert "lights.0.center" not in r.params  # a point light has none


@pytest.mark.parametrize("shape, name, value", [("rectangle", "size", [1.1, 0.3]), ("rectangle", "normal", [0.3, -1.0, 0.0]),
                                                ("disk", "radius", 0.45), ("sphere", "radius", 0.2)])
def test_an_area_lights_shape_set_renders_as_a_fresh_load(tmp_path, shape, name, value):
    """lights.<i>.size, normal and radius: the light's drawn triangles, its sample points, their normals and areas
    as a file saying the new shape gives them; a wrong shape of value is one line naming the parameter."""
    d = copy.deepcopy(doc())
    light = {"type": "area", "shape": shape, "center": [0.5, 2.5, 0.5], "radiance": [3.0, 2.5, 2.0]}
    light.update({"normal": [0.0, -1.0, 0.3], "size": [0.8, 0.5]} if shape == "rectangle" else
                 {"normal": [0.1, -1.0, 0.0], "radius": 0.3} if shape == "disk" else {"radius": 0.3})
    d["lights"] = [d["lights"][0], light]
    d["render"]["light_samples"] = 4
    r = warprt.Renderer(load(tmp_path, d), primary_query="raytrace")
    before = r.render()
    r.params[f"lights.1.{name}"] = value
    after = r.render()
    edited = copy.deepcopy(d)
    edited["lights"][1][name] = value
    assert_same_frame(after, warprt.render(load(tmp_path, edited, "edited.toml"), primary_query="raytrace"))
    assert not np.array_equal(after.image, before.image)
    with pytest.raises(warprt.SceneError, match=f"lights.1.{name}"):
        r.params[f"lights.1.{name}"] = [1.0, 2.0, 3.0, 4.0]


# --- An object's pose: objects.<name>.translation and rotation -------------------------------------------

POSE = {"objects.block.translation": [0.15, 0.05, -0.2], "objects.block.rotation": [0.2, 0.5, -0.1]}


def oracle_posed(rest: np.ndarray, t, w) -> np.ndarray:
    """The rest vertices turned by scipy's rotation vector about their bounding box's centre, then moved."""
    from scipy.spatial.transform import Rotation

    centre = (rest.min(0) + rest.max(0)) / 2
    return Rotation.from_rotvec(w).apply(rest - centre) + centre + np.asarray(t, np.float64)


def test_a_pose_is_zero_at_load_and_moves_the_vertices_about_their_centre(tmp_path):
    """translation and rotation read 0 at load; set, the vertices read R(w) (v - c) + c + t (c the rest
    vertices' bounding box centre, w a rotation vector as scipy's from_rotvec)."""
    r = warprt.Renderer(load(tmp_path, doc()))
    rest = r.params["objects.block.vertices"]
    assert np.array_equal(r.params["objects.block.translation"], np.zeros(3))
    assert np.array_equal(r.params["objects.block.rotation"], np.zeros(3))
    r.params.update(POSE)
    np.testing.assert_allclose(r.params["objects.block.vertices"],
                               oracle_posed(rest, POSE["objects.block.translation"], POSE["objects.block.rotation"]),
                               atol=1e-15)
    assert np.array_equal(r.params["objects.block.rotation"], POSE["objects.block.rotation"])


def test_a_pose_renders_as_a_fresh_load_of_its_posed_vertices(tmp_path):
    """The glass block posed: the BVH refit, the frame a fresh load's (the block as explicit triangles at the
    posed vertices) to the bit."""
    d = doc()
    r = warprt.Renderer(load(tmp_path, d), primary_query="raytrace")
    before = r.render()
    r.params.update(POSE)
    after = r.render()
    assert after.stats.geometry["bvh"] == "refit"
    edited = copy.deepcopy(d)
    edited["objects"][2] = {"name": "block", "shape": "triangles", "vertices": r.params["objects.block.vertices"].tolist(),
                            "faces": r.scene.objects[2].faces.tolist(), "material": "glass"}
    fresh = warprt.render(warprt.load_dict(edited, base=tmp_path), primary_query="raytrace")
    assert_same_frame(after, fresh)
    assert not np.array_equal(after.image, before.image)


def test_a_pose_is_absolute_and_keeps_the_rest_shape(tmp_path):
    """Each set replaces its part of the pose, about the same rest shape; a pose of 0 gives the rest vertices
    back to the bit."""
    r = warprt.Renderer(load(tmp_path, doc()))
    rest = r.params["objects.block.vertices"]
    r.params["objects.block.rotation"] = [0.0, 0.3, 0.0]
    r.params["objects.block.rotation"] = [0.0, 0.5, 0.0]  # not 0.8: absolute
    r.params["objects.block.translation"] = [0.0, 0.1, 0.0]
    np.testing.assert_allclose(r.params["objects.block.vertices"], oracle_posed(rest, [0.0, 0.1, 0.0], [0.0, 0.5, 0.0]),
                               atol=1e-15)
    r.params.update({"objects.block.translation": np.zeros(3), "objects.block.rotation": np.zeros(3)})
    assert np.array_equal(r.params["objects.block.vertices"], rest)


def test_setting_the_vertices_resets_the_pose(tmp_path):
    """Vertices set are the new rest shape, the pose 0 (a later pose turns about their centre); a pose set in
    the same update applies to them."""
    r = warprt.Renderer(load(tmp_path, doc()))
    r.params.update(POSE)
    given = r.params["objects.block.vertices"] * [1.0, 1.5, 1.0]
    r.params["objects.block.vertices"] = given
    assert np.array_equal(r.params["objects.block.vertices"], given)
    assert not r.params["objects.block.translation"].any() and not r.params["objects.block.rotation"].any()
    r.params["objects.block.rotation"] = [0.4, 0.0, 0.0]
    np.testing.assert_allclose(r.params["objects.block.vertices"], oracle_posed(given, np.zeros(3), [0.4, 0.0, 0.0]),
                               atol=1e-15)
    other = given + [0.0, 0.2, 0.0]
    r.params.update({"objects.block.vertices": other, "objects.block.translation": [0.1, 0.0, 0.0]})
    np.testing.assert_allclose(r.params["objects.block.vertices"], other + [0.1, 0.0, 0.0], atol=1e-15)
    assert not r.params["objects.block.rotation"].any()


def test_a_new_scene_starts_at_pose_zero_and_a_bad_pose_changes_nothing(tmp_path):
    """set_scene's objects have their own vertices: their poses read 0. A pose of the wrong shape is one
    SceneError naming it, the scene and the pose left as they were."""
    scene = load(tmp_path, doc())
    r = warprt.Renderer(scene)
    r.params.update(POSE)
    posed = r.scene
    with pytest.raises(warprt.SceneError, match="objects.block.rotation") as e:
        r.params.update({"objects.block.translation": [0.0, 0.0, 0.0], "objects.block.rotation": [1.0, 2.0]})
    assert "expected shape (3,), got (2,)" in str(e.value) and r.scene is posed
    assert np.array_equal(r.params["objects.block.translation"], POSE["objects.block.translation"])
    r.set_scene(scene)
    assert not r.params["objects.block.translation"].any() and not r.params["objects.block.rotation"].any()
    assert np.array_equal(r.params["objects.block.vertices"], scene.objects[2].vertices)


@pytest.mark.parametrize("name, value, message", [
    ("materials.red.kdd", [0, 0, 0], "unknown parameter (did you mean 'materials.red.kd'?)"),
    ("materials.red.ior", 1.5, "unknown parameter"),  # an opaque material has no ior
    ("lights.2.position", [0, 0, 0], "unknown parameter"),  # a directional light has no position
    ("materials.red.kd", [0.1, 0.2], "expected shape (3,), got (2,)"),
    ("camera.fovy", [30.0], "expected shape (), got (1,)"),
    ("objects.ball.vertices", np.zeros((3, 3)), "expected shape"),
    ("lights.0.color", [np.nan, 0.0, 0.0], "expected finite numbers"),
    ("materials.floor.kd_texture", np.zeros((4, 4)), "expected texels of shape (H, W, 3)"),
    ("camera.fovy", 190.0, "fovy"),  # the scene's own check, as a file saying it would get
])
def test_a_bad_parameter_is_one_scene_error_naming_it(tmp_path, name, value, message):
    r = warprt.Renderer(load(tmp_path, doc()))
    before = r.scene
    with pytest.raises(warprt.SceneError, match=rf"{name.split('.')[0]}") as e:
        r.params[name] = value
    assert message in str(e.value)
    assert r.scene is before  # nothing changed


def test_a_renderer_frame_is_a_fresh_render_whatever_came_before(tmp_path):
    """The frames of a Renderer that went through other views, lights and materials equal one-shot renders."""
    scene = load(tmp_path, doc())
    r = warprt.Renderer(scene)
    for name in ("camera.eye", "lights.0.color", "materials.red.kd"):
        r.params[name] = CASES[name][0]
        assert_same_frame(r.render(), warprt.render(r.scene))
    r.set_scene(scene)
    assert_same_frame(r.render(), warprt.render(scene))


@slow
def test_ka_following_kd_is_kept_only_where_the_file_left_ka_out(tmp_path):
    """The negative control for following: red says its ka, so setting kd leaves ka where it was."""
    r = warprt.Renderer(load(tmp_path, doc()))
    ka = r.params["materials.red.ka"]
    r.params["materials.red.kd"] = [0.0, 1.0, 0.0]
    assert np.array_equal(r.params["materials.red.ka"], ka)
    r.params["materials.floor.kd"] = [0.0, 1.0, 0.0]
    assert np.array_equal(r.params["materials.floor.ka"], [0.0, 1.0, 0.0])
