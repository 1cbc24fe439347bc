"""Writes the small assets the textured, vertex-coloured and file-normal scenes use (committed, so a
fresh clone renders them; rerun to regenerate: python scenes/assets.py). Every file is written here by
hand from its format's specification, not by the readers that load it.

    textures/bricks.png   64 x 64 sRGB bricks            meshes/crate.obj + .mtl  a box, per-face vt, map_Kd
    textures/globe.png   128 x 64 sRGB bands and dots    meshes/painted.ply       an icosphere, uchar colours
    meshes/tile.glb      a box, baseColorFactor x an embedded PNG, COLOR_0 on one node, 2 nodes of one mesh
    meshes/cube_flat.usda  a cube with faceVarying normals, UsdPreviewSurface <- UsdUVTexture (bricks)
    meshes/smooth_vn.obj   a cylinder with its analytic normals (vn) on the side, s off on the caps
    textures/sky.hdr     64 x 32 Radiance RGBE (flat), an equirectangular sky: blue above, brown ground, a sun
"""

from __future__ import annotations

import io
import json
import struct
from pathlib import Path

import numpy as np
from PIL import Image

HERE = Path(__file__).resolve().parent


def bricks(w: int = 64, h: int = 64) -> np.ndarray:
    """Staggered bricks in two reds, light mortar lines: 8-bit sRGB, row 0 at the top."""
    y, x = np.mgrid[0:h, 0:w]
    row = y // 8
    shift = (row % 2) * 8
    brick = ((x + shift) // 16 + row) % 2
    mortar = (y % 8 == 0) | ((x + shift) % 16 == 0)
    rgb = np.where(brick[..., None] == 0, [178, 62, 40], [140, 48, 34])
    rgb = np.where(mortar[..., None], [214, 206, 190], rgb)
    return rgb.astype(np.uint8)


def globe(w: int = 128, h: int = 64) -> np.ndarray:
    """Latitude bands with dots, so a uv sphere's seam and poles show."""
    y, x = np.mgrid[0:h, 0:w]
    band = (y * 6 // h) % 2
    rgb = np.where(band[..., None] == 0, [40, 90, 170], [230, 200, 80])
    dots = ((x % 16 - 8) ** 2 + (y % 16 - 8) ** 2) < 10
    rgb = np.where(dots[..., None], [30, 150, 60], rgb)
    return rgb.astype(np.uint8)


def png_bytes(rgb8: np.ndarray) -> bytes:
    out = io.BytesIO()
    Image.fromarray(rgb8).save(out, "PNG", optimize=True)
    return out.getvalue()


# A unit box, one quad per side (counter-clockwise from outside) with its uv corners.
BOX = np.array([[x, y, z] for x in (-0.5, 0.5) for y in (-0.5, 0.5) for z in (-0.5, 0.5)])
BOX_QUADS = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
QUAD_UV = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)]


def write_crate(folder: Path):
    lines = ["# a textured box: one vt per quad corner", "mtllib crate.mtl", "o crate"]
    lines += [f"v {x:g} {y:g} {z:g}" for x, y, z in BOX]
    lines += [f"vt {u:g} {v:g}" for u, v in QUAD_UV]
    lines += ["usemtl bricks", "s off"]
    lines += ["f " + " ".join(f"{i + 1}/{k + 1}" for k, i in enumerate(q)) for q in BOX_QUADS]
    (folder / "crate.obj").write_text("\n".join(lines) + "\n")
    # As Blender's exporter writes it: Kd 0.8 beside the map (the map replaces it), Ns 0 is no highlight.
    (folder / "crate.mtl").write_text("newmtl bricks\nNs 0.000000\nKa 1.000000 1.000000 1.000000\n"
                                      "Kd 0.800000 0.800000 0.800000\nKs 0.500000 0.500000 0.500000\n"
                                      "Ke 0.000000 0.000000 0.000000\nNi 1.450000\nd 1.000000\nillum 2\n"
                                      "map_Kd ../textures/bricks.png\n")


def icosphere(subdivisions: int = 2):
    t = (1.0 + 5.0**0.5) / 2.0
    v = np.array([[-1, t, 0], [1, t, 0], [-1, -t, 0], [1, -t, 0], [0, -1, t], [0, 1, t],
                  [0, -1, -t], [0, 1, -t], [t, 0, -1], [t, 0, 1], [-t, 0, -1], [-t, 0, 1]], np.float64)
    f = np.array([[0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11], [1, 5, 9], [5, 11, 4],
                  [11, 10, 2], [10, 7, 6], [7, 1, 8], [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8],
                  [3, 8, 9], [4, 9, 5], [2, 4, 11], [6, 2, 10], [8, 6, 7], [9, 8, 1]])
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    for _ in range(subdivisions):
        edges = np.sort(np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]]), axis=1)
        unique, inverse = np.unique(edges, axis=0, return_inverse=True)
        mid = v[unique].mean(axis=1)
        mid /= np.linalg.norm(mid, axis=1, keepdims=True)
        m = inverse.reshape(3, -1) + len(v)
        a, b, c = f[:, 0], f[:, 1], f[:, 2]
        f = np.concatenate([np.stack([a, m[0], m[2]], 1), np.stack([b, m[1], m[0]], 1),
                            np.stack([c, m[2], m[1]], 1), np.stack([m[0], m[1], m[2]], 1)])
        v = np.vstack([v, mid])
    return v, f


def write_painted(folder: Path):
    """Binary PLY: float x y z, uchar red green blue (sRGB-encoded, as PLY writers mean them)."""
    v, f = icosphere(2)
    rgb = np.clip(np.round(255 * (0.5 + 0.5 * v[:, [0, 1, 2]])), 0, 255).astype(np.uint8)
    rgb[:, 2] = 255 - rgb[:, 0] // 2
    rec = np.empty(len(v), dtype=[("x", "<f4"), ("y", "<f4"), ("z", "<f4"), ("r", "u1"), ("g", "u1"), ("b", "u1")])
    rec["x"], rec["y"], rec["z"] = (0.5 * v[:, k] for k in range(3))
    rec["r"], rec["g"], rec["b"] = rgb[:, 0], rgb[:, 1], rgb[:, 2]
    faces = np.empty(len(f), dtype=[("n", "u1"), ("i", "<i4", 3)])
    faces["n"], faces["i"] = 3, f
    header = (f"ply\nformat binary_little_endian 1.0\ncomment vertex colours, sRGB\nelement vertex {len(v)}\n"
              "property float x\nproperty float y\nproperty float z\nproperty uchar red\nproperty uchar green\n"
              f"property uchar blue\nelement face {len(f)}\nproperty list uchar int vertex_indices\nend_header\n")
    (folder / "painted.ply").write_bytes(header.encode() + rec.tobytes() + faces.tobytes())


def write_tile(folder: Path):
    """GLB: one box mesh (24 vertices, TEXCOORD_0 with glTF's v down), used by two nodes; the material's
    baseColorFactor times an embedded PNG; the second node's primitive also has COLOR_0."""
    positions, uvs, indices = [], [], []
    for q in BOX_QUADS:
        base = len(positions)
        positions += [BOX[i] for i in q]
        uvs += [(u, 1.0 - v) for u, v in QUAD_UV]
        indices += [base, base + 1, base + 2, base, base + 2, base + 3]
    positions = np.asarray(positions, np.float32)
    uvs = np.asarray(uvs, np.float32)
    indices = np.asarray(indices, np.uint16)
    colors = np.clip(0.5 + positions, 0.0, 1.0).astype(np.float32)  # linear, by the spec
    png = png_bytes(bricks())
    blob, views, accessors = bytearray(), [], []

    def add(data: bytes, accessor=None):
        while len(blob) % 4:
            blob.append(0)
        views.append({"buffer": 0, "byteOffset": len(blob), "byteLength": len(data)})
        blob.extend(data)
        if accessor is not None:
            accessors.append({"bufferView": len(views) - 1, **accessor})
        return len(accessors) - 1

    pos = add(positions.tobytes(), {"componentType": 5126, "count": len(positions), "type": "VEC3",
                                    "min": positions.min(0).tolist(), "max": positions.max(0).tolist()})
    tex = add(uvs.tobytes(), {"componentType": 5126, "count": len(uvs), "type": "VEC2"})
    col = add(colors.tobytes(), {"componentType": 5126, "count": len(colors), "type": "VEC3"})
    idx = add(indices.tobytes(), {"componentType": 5123, "count": len(indices), "type": "SCALAR"})
    add(png)
    doc = {
        "asset": {"version": "2.0", "generator": "warprt scenes/assets.py"},
        "scene": 0, "scenes": [{"nodes": [0, 1]}],
        "nodes": [{"name": "plain", "mesh": 0, "translation": [-0.7, 0.0, 0.0]},
                  {"name": "painted", "mesh": 1, "translation": [0.7, 0.0, 0.0], "rotation": [0.0, 0.3826834, 0.0, 0.9238795]}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": pos, "TEXCOORD_0": tex}, "indices": idx, "material": 0}]},
                   {"primitives": [{"attributes": {"POSITION": pos, "TEXCOORD_0": tex, "COLOR_0": col}, "indices": idx,
                                    "material": 0}]}],
        "materials": [{"name": "tile", "pbrMetallicRoughness": {"baseColorFactor": [0.9, 0.85, 0.7, 1.0],
                                                                "baseColorTexture": {"index": 0},
                                                                "metallicFactor": 0.0}}],
        "textures": [{"source": 0}],
        "images": [{"bufferView": len(views) - 1, "mimeType": "image/png"}],
        "accessors": accessors, "bufferViews": views, "buffers": [{"byteLength": len(blob)}],
    }
    while len(blob) % 4:
        blob.append(0)
    doc["buffers"][0]["byteLength"] = len(blob)
    js = json.dumps(doc, separators=(",", ":")).encode()
    js += b" " * (-len(js) % 4)
    out = struct.pack("<III", 0x46546C67, 2, 12 + 8 + len(js) + 8 + len(blob))
    out += struct.pack("<I4s", len(js), b"JSON") + js + struct.pack("<I4s", len(blob), b"BIN\0") + bytes(blob)
    (folder / "tile.glb").write_bytes(out)


def write_cube_usda(folder: Path):
    """USDA text: a cube whose normals are faceVarying (flat sides), st faceVarying, and a
    UsdPreviewSurface whose diffuseColor reads a UsdUVTexture through a UsdPrimvarReader_float2."""
    points = ", ".join(f"({x:g}, {y:g}, {z:g})" for x, y, z in BOX)
    indices = ", ".join(str(i) for q in BOX_QUADS for i in q)
    p = BOX[np.array(BOX_QUADS)]
    n = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    normals = ", ".join(f"({a:g}, {b:g}, {c:g})" for a, b, c in np.repeat(n, 4, 0))
    st = ", ".join(f"({u:g}, {v:g})" for _ in BOX_QUADS for u, v in QUAD_UV)
    text = f'''#usda 1.0
(
    defaultPrim = "World"
    metersPerUnit = 1
    upAxis = "Y"
)

def Xform "World"
{{
    def Mesh "Cube" (
        prepend apiSchemas = ["MaterialBindingAPI"]
    )
    {{
        int[] faceVertexCounts = [4, 4, 4, 4, 4, 4]
        int[] faceVertexIndices = [{indices}]
        point3f[] points = [{points}]
        normal3f[] primvars:normals = [{normals}] (
            interpolation = "faceVarying"
        )
        texCoord2f[] primvars:st = [{st}] (
            interpolation = "faceVarying"
        )
        uniform token subdivisionScheme = "none"
        rel material:binding = </World/Looks/Bricks>
    }}

    def Scope "Looks"
    {{
        def Material "Bricks"
        {{
            token outputs:surface.connect = </World/Looks/Bricks/Surface.outputs:surface>

            def Shader "Surface"
            {{
                uniform token info:id = "UsdPreviewSurface"
                color3f inputs:diffuseColor.connect = </World/Looks/Bricks/Texture.outputs:rgb>
                float inputs:roughness = 0.6
                token outputs:surface
            }}

            def Shader "Texture"
            {{
                uniform token info:id = "UsdUVTexture"
                asset inputs:file = @../textures/bricks.png@
                token inputs:sourceColorSpace = "sRGB"
                float2 inputs:st.connect = </World/Looks/Bricks/StReader.outputs:result>
                token inputs:wrapS = "repeat"
                token inputs:wrapT = "repeat"
                float3 outputs:rgb
            }}

            def Shader "StReader"
            {{
                uniform token info:id = "UsdPrimvarReader_float2"
                token inputs:varname = "st"
                float2 outputs:result
            }}
        }}
    }}
}}
'''
    (folder / "cube_flat.usda").write_text(text)


def write_smooth_vn(folder: Path, sections: int = 12):
    """A cylinder of radius 0.4 and height 1: its side's vn are the true radial normals (a renderer
    computing its own would tilt them at the rims), its caps flat ('s off')."""
    phi = np.arange(sections) * 2 * np.pi / sections
    ring = np.stack([0.4 * np.cos(phi), np.zeros(sections), -0.4 * np.sin(phi)], 1)
    v = np.vstack([ring + [0, -0.5, 0], ring + [0, 0.5, 0]])
    lines = ["# a cylinder with its analytic side normals", "o cylinder"]
    lines += [f"v {x:.6f} {y:.6f} {z:.6f}" for x, y, z in v]
    lines += [f"vn {np.cos(a):.6f} 0 {-np.sin(a):.6f}" for a in phi] + ["vn 0 -1 0", "vn 0 1 0"]
    lines.append("s 1")
    for i in range(sections):
        j = (i + 1) % sections
        lines.append(f"f {i + 1}//{i + 1} {j + 1}//{j + 1} {j + 1 + sections}//{j + 1} {i + 1 + sections}//{i + 1}")
    lines.append("s off")
    lines.append("f " + " ".join(f"{i + 1}//{sections + 1}" for i in reversed(range(sections))))
    lines.append("f " + " ".join(f"{i + 1 + sections}//{sections + 2}" for i in range(sections)))
    (folder / "smooth_vn.obj").write_text("\n".join(lines) + "\n")


def sky(w: int = 64, h: int = 32) -> np.ndarray:
    """Linear radiance, row 0 at the top (the +y pole): a sky brightening towards the horizon, a darker
    ground, and a 2 x 2-pixel sun of radiance 150 (about four times the sky's irradiance) 40 degrees up."""
    theta = (np.arange(h) + 0.5) / h * np.pi
    up = np.cos(theta)[:, None, None]
    sky = np.where(up > 0, np.array([0.25, 0.4, 0.8]) + (1 - up) * np.array([0.35, 0.3, 0.1]),
                   np.array([0.25, 0.2, 0.15]) * np.ones_like(up))
    img = np.broadcast_to(sky, (h, w, 3)).copy()
    img[10:12, 20:22] = [150.0, 140.0, 120.0]
    return img


def hdr_bytes(rgb: np.ndarray) -> bytes:
    """A flat (not run-length encoded) Radiance RGBE file: Ward's shared-exponent bytes, -Y H +X W."""
    h, w = rgb.shape[:2]
    peak = rgb.max(axis=2)
    mantissa, exponent = np.frexp(peak)  # peak = mantissa 2^exponent, mantissa in [0.5, 1)
    scale = np.where(peak > 1e-32, 256.0 / np.ldexp(1.0, exponent), 0.0)
    rgbe = np.zeros((h, w, 4), np.uint8)
    rgbe[..., :3] = np.floor(rgb * scale[..., None]).clip(0, 255)
    rgbe[..., 3] = np.where(peak > 1e-32, exponent + 128, 0)
    header = f"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y {h} +X {w}\n".encode()
    return header + rgbe.tobytes()


def main():
    (HERE / "textures").mkdir(exist_ok=True)
    (HERE / "textures" / "bricks.png").write_bytes(png_bytes(bricks()))
    (HERE / "textures" / "globe.png").write_bytes(png_bytes(globe()))
    (HERE / "textures" / "sky.hdr").write_bytes(hdr_bytes(sky()))
    meshes = HERE / "meshes"
    write_crate(meshes)
    write_painted(meshes)
    write_tile(meshes)
    write_cube_usda(meshes)
    write_smooth_vn(meshes)


if __name__ == "__main__":
    main()
