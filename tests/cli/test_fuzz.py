"""Fuzzing the scene and mesh readers: seeded mutations (truncation, byte flips, huge numbers, NaN and
Inf, wrong counts, lines lost or repeated, glTF JSON values changed) of valid TOML, OBJ (+MTL), PLY,
STL, glTF/GLB and USD files, each run through the command line's own code path (warprt.cli.main,
in-process, fd 2 captured) with a bounded time. Each must either render (exit 0, a complete 8x6
image, stderr only warnings and the summary) or be refused (exit 2, exactly one stderr line, a
'warprt: error:' one, and nothing written); never a traceback, an internal error or a hang.
"""

import json
import random
import re
import signal
import textwrap
from pathlib import Path

import pytest

from marks import slow
from scenekit import to_toml
from warprt.cli import main
from warprt.image import read_image

CASES_PER_SEED = 24
SECONDS_PER_CASE = 20  # a hang is a failure; the slowest cases (a first kernel compile) take a few seconds

SCENE = to_toml({
    "camera": {"eye": [2.0, 1.5, 4.0], "center": [0.0, 0.0, 0.0], "up": [0.0, 1.0, 0.0], "fovy": 45.0, "near": 1.0,
               "width": 8, "height": 6},
    "render": {"ambient": [0.1, 0.1, 0.1], "max_depth": 2, "spp": 1},
    "lights": [{"position": [4.0, 6.0, 4.0], "color": [1.0, 1.0, 1.0]}],
    "materials": {"red": {"kd": [0.7, 0.1, 0.1], "ks": [0.3, 0.3, 0.3], "shininess": 32.0, "reflectivity": 0.2}},
    "objects": [
        {"shape": "sphere", "radius": 0.5, "subdivisions": 1, "material": "red", "translate": [0.5, 0.0, 0.0]},
        {"mesh": "tri.obj", "material": "red", "scale": [1.0, 2.0, 1.0], "rotate": [0.0, 30.0, 0.0]},
        {"shape": "triangles", "vertices": [[-1.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], "faces": [[0, 1, 2]]},
    ],
})

OBJ = "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvn 0 0 1\nusemtl paint\nf 1//1 2//1 3//1\nusemtl mirror\nf 1//1 3//1 4//1\n"
MTL = "newmtl paint\nKa 0.1 0.1 0.1\nKd 0.8 0.2 0.2\nKs 0.5 0.5 0.5\nNs 40\nillum 2\nnewmtl mirror\nKd 0.1 0.1 0.1\nKs 0.9 0.9 0.9\nillum 3\n"

USDA = textwrap.dedent("""\
    #usda 1.0
    (
        upAxis = "Y"
    )

    def Xform "root"
    {
        double3 xformOp:translate = (0, 0.5, 0)
        uniform token[] xformOpOrder = ["xformOp:translate"]

        def Mesh "quad" (
            prepend apiSchemas = ["MaterialBindingAPI"]
        )
        {
            point3f[] points = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (0.5, 1.5, 0)]
            int[] faceVertexCounts = [4, 3]
            int[] faceVertexIndices = [0, 1, 2, 3, 3, 2, 4]
            rel material:binding = </root/paint>
        }

        def Mesh "tri"
        {
            point3f[] points = [(2, 0, 0), (3, 0, 0), (2, 1, 0)]
            int[] faceVertexCounts = [3]
            int[] faceVertexIndices = [0, 1, 2]
            color3f[] primvars:displayColor = [(0.2, 0.6, 0.2)]
        }

        def Material "paint"
        {
            token outputs:surface.connect = </root/paint/shader.outputs:surface>
            def Shader "shader"
            {
                uniform token info:id = "UsdPreviewSurface"
                color3f inputs:diffuseColor = (0.7, 0.3, 0.1)
                token outputs:surface
            }
        }
    }
    """)


def _seeds(folder: Path) -> dict:
    """The valid files, by name: {name: (bytes, companions {name: bytes} written beside it)}."""
    import trimesh
    from pxr import Usd
    from trimesh.exchange.gltf import export_gltf

    box = trimesh.creation.box()
    box.visual = trimesh.visual.TextureVisuals(material=trimesh.visual.material.PBRMaterial(
        name="clay", baseColorFactor=[0.5, 0.4, 0.3, 1.0]))
    (folder / "seed.usda").write_text(USDA)
    Usd.Stage.Open(str(folder / "seed.usda")).Export(str(folder / "seed.usdc"))
    tri = {"tri.obj": b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"}
    return {
        "scene.toml": (SCENE.encode(), tri),
        "mesh.obj": (OBJ.encode(), {"m.mtl": MTL.encode()}),
        "mesh.mtl": (MTL.encode(), {"mesh.obj": OBJ.replace("m.mtl", "mesh.mtl").encode()}),
        "ascii.ply": (box.export(file_type="ply", encoding="ascii"), {}),
        "binary.ply": (box.export(file_type="ply"), {}),
        "ascii.stl": (box.export(file_type="stl_ascii").encode() if isinstance(box.export(file_type="stl_ascii"), str)
                      else box.export(file_type="stl_ascii"), {}),
        "binary.stl": (box.export(file_type="stl"), {}),
        "mesh.gltf": (export_gltf(trimesh.Scene(box), embed_buffers=True)["model.gltf"], {}),
        "mesh.glb": (box.export(file_type="glb"), {}),
        "stage.usda": (USDA.encode(), {}),
        "stage.usdc": ((folder / "seed.usdc").read_bytes(), {}),
    }


WEIRD_NUMBERS = ["1e308", "-1e308", "nan", "inf", "-inf", "1e39", "-1e39", "0", "-1", "4294967296",
                 "99999999999999999999", "1e-320", "3.0e12", "-0"]
NUMBER = re.compile(rb"(?<![A-Za-z_])-?\d+(?:\.\d*)?(?:[eE][-+]?\d+)?")


def _numbers(data: bytes, rng, how):
    spans = [m.span() for m in NUMBER.finditer(data)]
    if not spans:
        return data
    out = bytearray(data)
    for a, b in sorted(rng.sample(spans, min(len(spans), rng.randint(1, 3))), reverse=True):
        out[a:b] = how(bytes(out[a:b]), rng).encode()
    return bytes(out)


def _weird(_, rng):
    return rng.choice(WEIRD_NUMBERS)


def _wrong_count(token: bytes, rng):
    """An integer made wrong the way counts go wrong: zero, one more, doubled, vast, negative."""
    try:
        n = int(float(token))
    except ValueError:
        n = 1
    return str(rng.choice([0, n + 1, n - 1, 2 * n, n * 1000, -n, 2**31]))


def _lines(data: bytes, rng):
    lines = data.split(b"\n")
    i = rng.randrange(len(lines))
    op = rng.choice(["drop", "repeat", "swap"])
    if op == "drop":
        del lines[i]
    elif op == "repeat":
        lines.insert(i, lines[i])
    else:
        j = rng.randrange(len(lines))
        lines[i], lines[j] = lines[j], lines[i]
    return b"\n".join(lines)


def _json_value(data: bytes, rng):
    """glTF: one value of the JSON (a count, an index, an offset, a colour) changed."""
    try:
        doc = json.loads(data)
    except ValueError:
        return data
    leaves = []

    def walk(node, path):
        items = node.items() if isinstance(node, dict) else enumerate(node) if isinstance(node, list) else ()
        for k, v in items:
            if isinstance(v, (dict, list)):
                walk(v, path + [k])
            else:
                leaves.append((node, k))

    walk(doc, [])
    node, key = rng.choice(leaves)
    v = node[key]
    node[key] = rng.choice([None, "x", -1, 0, 10**9, 1e308, float("nan"), [], 2 * v if isinstance(v, int) else v])
    return json.dumps(doc).encode()


def _binary_count(data: bytes, rng):
    """A binary STL's triangle count, or a GLB's declared lengths, made wrong."""
    out = bytearray(data)
    at = 80 if data[:4] != b"glTF" else rng.choice([8, 12])
    n = int.from_bytes(out[at:at + 4], "little")
    out[at:at + 4] = (rng.choice([0, n + 1, n - 1, 2 * n, 2**32 - 1]) % 2**32).to_bytes(4, "little")
    return bytes(out)


def mutate(name: str, data: bytes, rng) -> tuple[str, bytes]:
    text = not (name.startswith("binary") or name.endswith((".glb", ".usdc")))
    ops = ["truncate", "flip"]
    ops += ["weird number", "wrong count", "lines"] if text else ["binary count"] if name.endswith((".stl", ".glb")) else []
    if name.endswith(".gltf"):
        ops += ["json value", "json value"]
    if name.endswith(".glb"):
        ops += ["weird number"]  # its JSON chunk is text
    op = rng.choice(ops)
    if op == "truncate":
        return op, data[:rng.randrange(len(data))]
    if op == "flip":
        out = bytearray(data)
        for _ in range(rng.randint(1, 8)):
            out[rng.randrange(len(out))] = rng.randrange(256)
        return op, bytes(out)
    if op == "weird number":
        return op, _numbers(data, rng, _weird)
    if op == "wrong count":
        return op, _numbers(data, rng, _wrong_count)
    if op == "lines":
        return op, _lines(data, rng)
    if op == "json value":
        return op, _json_value(data, rng)
    return op, _binary_count(data, rng)


SEED_NAMES = ["scene.toml", "mesh.obj", "mesh.mtl", "ascii.ply", "binary.ply", "ascii.stl", "binary.stl",
              "mesh.gltf", "mesh.glb", "stage.usda", "stage.usdc"]
CASES = [(name, k) for name in SEED_NAMES for k in range(CASES_PER_SEED)]


@pytest.fixture(scope="module")
def seeds(tmp_path_factory):
    return _seeds(tmp_path_factory.mktemp("seeds"))


class _Hang(BaseException):
    """Raised by the alarm in the case's own thread: not an Exception, so main() cannot report it."""


def _alarm(signum, frame):
    raise _Hang()


def _files(folder: Path) -> set:
    return {p.name for p in folder.iterdir()}


@slow
def test_the_seeds_render(seeds, tmp_path, capfd):
    """The negative control: unmutated, every seed renders, so a refusal below is the mutation's."""
    for name, (data, companions) in seeds.items():
        folder = tmp_path / name.replace(".", "_")
        folder.mkdir()
        for other, content in companions.items():
            (folder / other).write_bytes(content)
        (folder / name).write_bytes(data)
        target = name if name != "mesh.mtl" else "mesh.obj"
        code = main(["render", str(folder / target), "-o", str(folder / "out.png"), "--width", "8", "--height", "6"])
        err = capfd.readouterr().err
        assert code == 0 and "warprt: warning" not in err, (name, err)


@pytest.mark.parametrize("name,k", CASES, ids=[f"{n}-{k}" for n, k in CASES])
def test_a_mutated_file_renders_or_is_refused_in_one_line(seeds, tmp_path, capfd, name, k):
    rng = random.Random(f"{name}/{k}")
    data, companions = seeds[name]
    op, mutated = mutate(name, data, rng)
    for other, content in companions.items():
        (tmp_path / other).write_bytes(content)
    (tmp_path / name).write_bytes(mutated)
    target = tmp_path / (name if name != "mesh.mtl" else "mesh.obj")
    before = _files(tmp_path)
    capfd.readouterr()
    previous = signal.signal(signal.SIGALRM, _alarm)
    signal.setitimer(signal.ITIMER_REAL, SECONDS_PER_CASE)
    try:
        code = main(["render", str(target), "-o", str(tmp_path / "out.png"), "--width", "8", "--height", "6"])
    except _Hang:
        pytest.fail(f"{name} ({op}): no answer within {SECONDS_PER_CASE} s")
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)
    out, err = capfd.readouterr()
    lines = err.splitlines()
    what = f"{name} ({op}): exit {code}, stderr {err!r}"
    assert "Traceback" not in err and "internal error" not in err, what
    if code == 0:
        assert read_image(tmp_path / "out.png").shape == (6, 8, 3), what
        assert lines and lines[-1].startswith(f"wrote {tmp_path / 'out.png'} (8x6"), what
        assert all(line.startswith("warprt: warning: ") for line in lines[:-1]), what
        assert _files(tmp_path) == before | {"out.png"}, what
    else:
        assert code == 2, what
        assert len(lines) == 1 and lines[0].startswith("warprt: error: "), what
        assert _files(tmp_path) == before, what  # no image, no temporary file
