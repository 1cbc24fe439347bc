"""What mesh files say about glass: MTL's illum 4/6/7, Ni and Tf; glTF's KHR_materials_transmission and
KHR_materials_ior; USD's UsdPreviewSurface ior and opacity. Each mapping on values written here (dicts,
JSON, an in-memory stage), then through a real file the test writes and the scene reads back."""

import base64
import json

import numpy as np
import pytest

import warprt
from warprt.scene import DEFAULT_IOR, dielectric_from_gltf, dielectric_from_mtl, dielectric_from_usd, read_mesh_file

# --- MTL -------------------------------------------------------------------------------------------------


def test_mtl_illum_4_6_7_make_a_dielectric_of_index_ni_and_transmittance_tf():
    for illum in ("4", "6", "7"):
        assert dielectric_from_mtl({"illum": [illum], "ni": ["1.33"], "tf": ["0.9", "0.8", "0.7"]}) == {
            "ior": 1.33, "reflectivity": (0.0, 0.0, 0.0), "transmittance": (0.9, 0.8, 0.7)}
    assert dielectric_from_mtl({"illum": ["7"], "tf": ["0.5"]})["transmittance"] == (0.5, 0.5, 0.5)
    assert dielectric_from_mtl({"illum": ["4"]}) == {"ior": DEFAULT_IOR, "reflectivity": (0.0, 0.0, 0.0)}


def test_mtl_ni_without_a_refracting_illum_is_opaque():
    """Exporters write Ni for every material; only illum 4, 6 and 7 trace a refracted ray."""
    for illum in ("0", "1", "2", "3", "5"):
        assert dielectric_from_mtl({"illum": [illum], "ni": ["1.45"]}) == {}
    assert dielectric_from_mtl({"ni": ["1.45"]}) == {}


@pytest.mark.parametrize("raw, field", [({"illum": ["7"], "ni": ["0"]}, "Ni"), ({"illum": ["7"], "ni": ["glass"]}, "Ni"),
                                        ({"illum": ["7"], "tf": ["1.5", "1", "1"]}, "Tf"),
                                        ({"illum": ["7"], "tf": ["spectral", "glass.rfl"]}, "Tf")])
def test_bad_mtl_glass_values_name_the_statement(raw, field):
    with pytest.raises(warprt.SceneError) as e:
        dielectric_from_mtl(raw, "cup.mtl", "glass")
    assert e.value.source == "cup.mtl" and e.value.field == f"newmtl glass: {field}"


def test_obj_with_an_mtl_glass_reads_as_a_dielectric(tmp_path):
    (tmp_path / "cup.obj").write_text("mtllib cup.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl glass\nf 1 2 3\n")
    (tmp_path / "cup.mtl").write_text("newmtl glass\nKa 0 0 0\nKd 0 0 0\nKs 0.5 0.5 0.5\nNs 200\nNi 1.52\n"
                                      "Tf 0.9 0.95 1.0\nillum 7\n")
    (glass,) = (m for _, m in read_mesh_file(tmp_path / "cup.obj").materials)
    assert (glass.ior, glass.transmittance, glass.reflectivity) == (1.52, (0.9, 0.95, 1.0), (0.0, 0.0, 0.0))
    assert (glass.kd, glass.ks, glass.shininess) == ((0.0, 0.0, 0.0), (0.5, 0.5, 0.5), 200.0)


# --- glTF ------------------------------------------------------------------------------------------------

GLASS_JSON = {"name": "glass", "pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.9, 1.0, 1.0]},
              "extensions": {"KHR_materials_transmission": {"transmissionFactor": 0.75},
                             "KHR_materials_ior": {"ior": 1.4}}}


def test_gltf_transmission_makes_a_dielectric_tinted_by_the_base_colour():
    got = dielectric_from_gltf(GLASS_JSON)
    assert got["ior"] == 1.4
    assert np.allclose(got["transmittance"], [0.6, 0.675, 0.75]) and np.allclose(got["kd"], [0.2, 0.225, 0.25])
    assert got["ka"] == got["kd"]
    plain = {**GLASS_JSON, "extensions": {"KHR_materials_transmission": {"transmissionFactor": 1.0}}}
    assert dielectric_from_gltf(plain)["ior"] == DEFAULT_IOR  # KHR_materials_ior's default
    assert dielectric_from_gltf({**GLASS_JSON, "extensions": {"KHR_materials_ior": {"ior": 1.4}}}) == {}  # no transmission
    assert dielectric_from_gltf({"extensions": {"KHR_materials_transmission": {}}}) == {}  # transmissionFactor 0
    assert dielectric_from_gltf({}) == {}


def test_bad_gltf_glass_values_name_the_field():
    with pytest.raises(warprt.SceneError, match=r"KHR_materials_ior\.ior: expected a number > 0, got -1"):
        dielectric_from_gltf({"extensions": {"KHR_materials_transmission": {"transmissionFactor": 1.0},
                                             "KHR_materials_ior": {"ior": -1}}}, "cup.gltf", "materials[0]")
    with pytest.raises(warprt.SceneError, match=r"transmissionFactor: expected a number in \[0, 1\]"):
        dielectric_from_gltf({"extensions": {"KHR_materials_transmission": {"transmissionFactor": 2}}})


def test_gltf_file_with_transmission_reads_as_a_dielectric(tmp_path):
    """A .gltf written by hand: one triangle, its buffer inline, the material's extensions as glTF
    writes them (trimesh does not keep them: they are read from the JSON)."""
    positions = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], np.float32).tobytes()
    doc = {
        "asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "material": 0}]}],
        "materials": [GLASS_JSON], "extensionsUsed": ["KHR_materials_transmission", "KHR_materials_ior"],
        "buffers": [{"byteLength": len(positions),
                     "uri": "data:application/octet-stream;base64," + base64.b64encode(positions).decode()}],
        "bufferViews": [{"buffer": 0, "byteLength": len(positions)}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                       "min": [0, 0, 0], "max": [1, 1, 0]}],
    }
    (tmp_path / "cup.gltf").write_text(json.dumps(doc))
    (glass,) = (m for _, m in read_mesh_file(tmp_path / "cup.gltf").materials)
    assert glass.ior == pytest.approx(1.4)
    assert np.allclose(glass.transmittance, [0.6, 0.675, 0.75]) and np.allclose(glass.kd, [0.2, 0.225, 0.25])


# --- USD -------------------------------------------------------------------------------------------------


def preview_surface(stage, name, **inputs):
    from pxr import Gf, Sdf, UsdShade

    material = UsdShade.Material.Define(stage, f"/looks/{name}")
    shader = UsdShade.Shader.Define(stage, f"/looks/{name}/surface")
    shader.CreateIdAttr("UsdPreviewSurface")
    for key, value in inputs.items():
        if key == "diffuseColor":
            shader.CreateInput(key, Sdf.ValueTypeNames.Color3f).Set(Gf.Vec3f(*value))
        else:
            shader.CreateInput(key, Sdf.ValueTypeNames.Float).Set(value)
    material.CreateSurfaceOutput().ConnectToSource(shader.ConnectableAPI(), "surface")
    return material, shader


def test_usd_preview_surface_with_opacity_below_1_is_a_dielectric():
    pytest.importorskip("pxr")
    from pxr import Usd

    stage = Usd.Stage.CreateInMemory()
    _, glass = preview_surface(stage, "glass", ior=1.45, opacity=0.2, diffuseColor=(0.5, 0.25, 1.0))
    got = dielectric_from_usd(glass)
    assert got["ior"] == pytest.approx(1.45) and np.allclose(got["transmittance"], 0.8)
    assert np.allclose(got["kd"], [0.1, 0.05, 0.2]) and got["ka"] == got["kd"]
    assert dielectric_from_usd(preview_surface(stage, "clear", opacity=0.0)[1])["ior"] == DEFAULT_IOR
    assert dielectric_from_usd(preview_surface(stage, "opaque", ior=1.45)[1]) == {}  # opacity 1 by default
    # An opacity threshold makes opacity a cut-out mask, not a transparent medium.
    assert dielectric_from_usd(preview_surface(stage, "masked", opacity=0.2, opacityThreshold=0.5)[1]) == {}


def test_usd_file_with_a_transparent_preview_surface_reads_as_a_dielectric(tmp_path):
    pytest.importorskip("pxr")
    from pxr import Usd, UsdGeom, UsdShade

    path = tmp_path / "cup.usda"
    stage = Usd.Stage.CreateNew(str(path))
    mesh = UsdGeom.Mesh.Define(stage, "/cup")
    mesh.CreatePointsAttr([(0, 0, 0), (1, 0, 0), (0, 1, 0)])
    mesh.CreateFaceVertexCountsAttr([3])
    mesh.CreateFaceVertexIndicesAttr([0, 1, 2])
    material, _ = preview_surface(stage, "glass", ior=1.5, opacity=0.0)
    UsdShade.MaterialBindingAPI.Apply(mesh.GetPrim()).Bind(material)
    stage.GetRootLayer().Save()
    (glass,) = (m for _, m in read_mesh_file(path).materials)
    assert (glass.ior, glass.transmittance, glass.kd) == (1.5, (1.0, 1.0, 1.0), (0.0, 0.0, 0.0))
