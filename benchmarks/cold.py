"""Cold start against Mitsuba: process start to image file, every compiled-kernel cache warm, on the
default scene and on a scene of five PLY and OBJ files that each side reads with its own readers.

The default scene (640x480): `warprt render -o x.png` against the same scene through Mitsuba's Python
API (head_to_head's script). The mesh scene (1024x768, about 93k triangles in three binary PLY files,
one with vertex colours, and two OBJ files): `warprt render scene.toml` against a script such as a
Mitsuba user writes, whose shapes are Mitsuba's own `ply` and `obj` plugins (no Python mesh parsing)
and whose integrator is the reference's Whitted one. The two commands run in turn, A B A B, after one
untimed run of each; the ratio is the median of the pairs' ratios.

    python -m benchmarks.cold [--repeat 7]
"""

from __future__ import annotations

import argparse
import itertools
import json
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from benchmarks.head_to_head import ENV, MITSUBA_COLD, REPO
from benchmarks.output import save

ROOT = Path(__file__).resolve().parent

# A Mitsuba user's script for the mesh scene: the meshes through Mitsuba's plugins, placed as the scene
# file places them (scale, then rotate about x, y, z, then translate); camera, lights and materials
# from the same file; the reference's Whitted integrator (same terms, shadows, mirrors, ray levels).
MITSUBA_FILES = """
import sys, tomllib
from pathlib import Path
from types import SimpleNamespace as NS
from reference.mitsuba_whitted import Switches, mitsuba, whitted_integrator
mi, dr = mitsuba()
path = Path(sys.argv[1])
doc = tomllib.loads(path.read_text())
shapes, objects = {}, []
for i, o in enumerate(doc["objects"]):
    rx, ry, rz = o.get("rotate", [0.0, 0.0, 0.0])
    to_world = (mi.ScalarTransform4f().translate(o.get("translate", [0.0, 0.0, 0.0]))
                @ mi.ScalarTransform4f().rotate([0, 0, 1], rz) @ mi.ScalarTransform4f().rotate([0, 1, 0], ry)
                @ mi.ScalarTransform4f().rotate([1, 0, 0], rx) @ mi.ScalarTransform4f().scale(o.get("scale", 1.0)))
    shapes[f"object_{i}"] = {"type": Path(o["mesh"]).suffix[1:], "filename": str(path.parent / o["mesh"]),
                             "to_world": to_world, "face_normals": not o.get("smooth", False)}
    objects.append(NS(material=o["material"]))
emitters = {f"light_{i:03d}": {"type": "point", "position": l["position"], "intensity": {"type": "rgb", "value": l["color"]}}
            for i, l in enumerate(doc["lights"])}
scene = mi.load_dict({"type": "scene", **shapes, **emitters})
c, r = doc["camera"], doc["render"]
sensor = mi.load_dict({"type": "perspective", "fov_axis": "y", "fov": c["fovy"], "near_clip": 1e-3, "far_clip": 1e4,
                       "to_world": mi.ScalarTransform4f().look_at(origin=c["eye"], target=c["center"], up=c["up"]),
                       "film": {"type": "hdrfilm", "width": c["width"], "height": c["height"], "rfilter": {"type": "box"},
                                "pixel_format": "rgb", "component_format": "float32"},
                       "sampler": {"type": "stratified", "sample_count": 1, "jitter": False}})
material = lambda m: NS(ka=m.get("ka", m["kd"]), kd=m["kd"], ks=m["ks"], shininess=m["shininess"],
                        reflectivity=[m.get("reflectivity", 0.0)] * 3, ior=None, textures={}, double_sided=True)
tables = NS(lights=[NS(position=l["position"], color=l["color"], type="point", falloff="none") for l in doc["lights"]],
            render=NS(ambient=r["ambient"], background=r["background"]),
            materials={k: material(m) for k, m in doc["materials"].items()}, objects=objects)
integrator = whitted_integrator(scene, tables, {f"object_{i}": i for i in range(len(objects))},
                                Switches(max_depth=r["max_depth"], vertex_color=False, texture=False))
image = mi.render(scene, sensor=sensor, integrator=integrator, spp=1, seed=0)
mi.util.write_bitmap(sys.argv[2], image[:, :, :3])  # an sRGB PNG, as warprt writes
"""

WIDTH, HEIGHT = 1024, 768

SCENE = """# Five mesh files as a user brings them: three binary PLY (vertex colours, normals, uvs) and two OBJ
# (v/vt/vn triangles, bare quads); written by benchmarks/cold.py.

[camera]
eye = [0.0, 3.2, 9.0]
center = [0.0, 0.9, 0.0]
up = [0.0, 1.0, 0.0]
fovy = 45.0
width = {width}
height = {height}

[render]
ambient = [0.08, 0.08, 0.08]
background = [0.02, 0.03, 0.06]
max_depth = 3
spp = 1

[[lights]]
position = [4.0, 7.0, 5.0]
color = [0.8, 0.8, 0.8]

[[lights]]
position = [-6.0, 4.0, 3.0]
color = [0.35, 0.35, 0.45]

[materials.ground]
kd = [0.5, 0.5, 0.5]
ks = [0.1, 0.1, 0.1]
shininess = 16.0
reflectivity = 0.15

[materials.red]
kd = [0.75, 0.12, 0.1]
ks = [0.6, 0.6, 0.6]
shininess = 64.0

[materials.gold]
kd = [0.7, 0.55, 0.2]
ks = [0.8, 0.7, 0.4]
shininess = 90.0

[materials.blue]
kd = [0.15, 0.25, 0.7]
ks = [0.3, 0.3, 0.3]
shininess = 24.0

[materials.chrome]
kd = [0.05, 0.05, 0.05]
ks = [0.5, 0.5, 0.5]
shininess = 128.0
reflectivity = 0.7

[[objects]]
mesh = "terrain.ply"
material = "ground"

[[objects]]
mesh = "blob.ply"
material = "red"
smooth = true
translate = [-2.2, 1.1, 0.0]

[[objects]]
mesh = "knot.ply"
material = "gold"
smooth = true
rotate = [20.0, 0.0, 0.0]
translate = [0.2, 1.3, -0.8]

[[objects]]
mesh = "torus.obj"
material = "blue"
smooth = true
rotate = [70.0, 30.0, 0.0]
translate = [2.4, 0.8, 0.6]

[[objects]]
mesh = "vase.obj"
material = "chrome"
smooth = true
translate = [0.9, 0.0, 1.8]
"""


# --- the mesh files ------------------------------------------------------------------------------------


def _grid_quads(nu: int, nv: int, wrap_u: bool = False, wrap_v: bool = False) -> np.ndarray:
    """nu x nv quads, counter-clockwise in (u, v), over a grid of vertices stored row by row (v rows of u);
    a wrapped direction has nu (nv) vertices and closes on itself."""
    cu, cv = nu + (not wrap_u), nv + (not wrap_v)
    u, v = np.meshgrid(np.arange(nu), np.arange(nv))
    at = lambda u, v: (v % cv) * cu + u % cu
    return np.stack([at(u, v), at(u + 1, v), at(u + 1, v + 1), at(u, v + 1)], -1).reshape(-1, 4)


def _normals(v: np.ndarray, tri: np.ndarray) -> np.ndarray:
    n = np.zeros_like(v)
    fn = np.cross(v[tri[:, 1]] - v[tri[:, 0]], v[tri[:, 2]] - v[tri[:, 0]])
    for k in range(3):
        np.add.at(n, tri[:, k], fn)
    return n / np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-12)


def _triangles(quads: np.ndarray) -> np.ndarray:
    return np.concatenate([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]])


def _write_ply(path: Path, vertex: dict, faces: np.ndarray):
    """Binary little-endian PLY: vertex properties {name: (ply type, values)}, faces of equal length."""
    types = {"float": "<f4"}
    rec = np.empty(len(next(iter(vertex.values()))[1]), [(k, types[t]) for k, (t, _) in vertex.items()])
    for k, (_, values) in vertex.items():
        rec[k] = values
    face = np.empty(len(faces), [("n", "u1"), ("i", "<i4", faces.shape[1])])
    face["n"], face["i"] = faces.shape[1], faces
    head = ["ply", "format binary_little_endian 1.0", f"element vertex {len(rec)}"]
    head += [f"property {t} {k}" for k, (t, _) in vertex.items()]
    head += [f"element face {len(faces)}", "property list uchar int vertex_indices", "end_header"]
    path.write_bytes(("\n".join(head) + "\n").encode() + rec.tobytes() + face.tobytes())


def write_mesh_scene(folder: Path, width: int = WIDTH, height: int = HEIGHT) -> Path:
    """The five mesh files and scene.toml (image width x height) in ``folder``; returns the scene file."""
    folder.mkdir(parents=True, exist_ok=True)
    # terrain.ply: 160 x 120 quads of a gentle heightfield as triangles, a colour per vertex (float: Mitsuba's
    # ply plugin warns that 8-bit colours are not in [0, 1]).
    nu, nv = 160, 120
    x, z = np.meshgrid(np.linspace(-8, 8, nu + 1), np.linspace(-6, 6, nv + 1))
    y = 0.15 * np.sin(0.9 * x) * np.cos(0.7 * z) - 0.15
    rgb = np.stack([0.5 + 0.4 * np.sin(x), 0.6 + 0.3 * np.cos(z), 0.5 + 0.2 * np.sin(x + z)], -1).reshape(-1, 3)
    tri = _triangles(_grid_quads(nu, nv)[:, ::-1])  # counter-clockwise seen from above (+y); Mitsuba's ply reads triangles only
    _write_ply(folder / "terrain.ply", {"x": ("float", x.ravel()), "y": ("float", y.ravel()), "z": ("float", z.ravel()),
                                        **{c: ("float", rgb[:, k]) for k, c in enumerate(("red", "green", "blue"))}},
               tri)
    # blob.ply: a lumpy sphere, 128 x 64 quads as triangles, with its normals.
    th, ph = np.meshgrid(np.linspace(0, 2 * np.pi, 128, endpoint=False), np.linspace(0.02, np.pi - 0.02, 65))
    radius = 1.0 + 0.08 * np.sin(5 * th) * np.sin(4 * ph)
    v = np.stack([radius * np.sin(ph) * np.cos(th), radius * np.cos(ph), radius * np.sin(ph) * np.sin(th)], -1).reshape(-1, 3)
    tri = _triangles(_grid_quads(128, 64, wrap_u=True)[:, ::-1])
    n = _normals(v, tri)
    _write_ply(folder / "blob.ply", {**{c: ("float", v[:, k]) for k, c in enumerate("xyz")},
                                     **{c: ("float", n[:, k]) for k, c in enumerate(("nx", "ny", "nz"))}}, tri)
    # knot.ply: a (2, 3) torus knot tube, 512 x 16 quads as triangles, with uvs.
    t, s = np.meshgrid(np.linspace(0, 2 * np.pi, 512, endpoint=False), np.linspace(0, 2 * np.pi, 16, endpoint=False))
    centre = lambda t: np.stack([(2 + np.cos(3 * t)) * np.cos(2 * t), np.sin(3 * t), (2 + np.cos(3 * t)) * np.sin(2 * t)], -1) * 0.45
    c0, c1 = centre(t), centre(t + 1e-3)
    tangent = (c1 - c0) / np.linalg.norm(c1 - c0, axis=-1, keepdims=True)
    side = np.cross(tangent, [0.0, 1.0, 0.0])
    side /= np.linalg.norm(side, axis=-1, keepdims=True)
    up = np.cross(side, tangent)
    v = (c0 + 0.16 * (np.cos(s)[..., None] * side + np.sin(s)[..., None] * up)).reshape(-1, 3)
    tri = _triangles(_grid_quads(512, 16, wrap_u=True, wrap_v=True))
    _write_ply(folder / "knot.ply", {**{c: ("float", v[:, k]) for k, c in enumerate("xyz")},
                                     "s": ("float", (t / (2 * np.pi)).ravel()), "t": ("float", (s / (2 * np.pi)).ravel())}, tri)
    # torus.obj: 96 x 48 quads as triangles, v/vt/vn.
    a, b = np.meshgrid(np.linspace(0, 2 * np.pi, 96, endpoint=False), np.linspace(0, 2 * np.pi, 48, endpoint=False))
    v = np.stack([(0.8 + 0.3 * np.cos(b)) * np.cos(a), 0.3 * np.sin(b), (0.8 + 0.3 * np.cos(b)) * np.sin(a)], -1).reshape(-1, 3)
    n = np.stack([np.cos(b) * np.cos(a), np.sin(b), np.cos(b) * np.sin(a)], -1).reshape(-1, 3)
    uv = np.stack([a / (2 * np.pi), b / (2 * np.pi)], -1).reshape(-1, 2)
    tri = _triangles(_grid_quads(96, 48, wrap_u=True, wrap_v=True)[:, ::-1]) + 1
    lines = [f"v {p[0]:.6f} {p[1]:.6f} {p[2]:.6f}" for p in v] + [f"vt {p[0]:.6f} {p[1]:.6f}" for p in uv]
    lines += [f"vn {p[0]:.6f} {p[1]:.6f} {p[2]:.6f}" for p in n] + [f"f {a}/{a}/{a} {b}/{b}/{b} {c}/{c}/{c}" for a, b, c in tri]
    (folder / "torus.obj").write_text("\n".join(lines) + "\n")
    # vase.obj: a surface of revolution, 96 x 64 quads, positions only (normals computed by each reader).
    h, a = np.meshgrid(np.linspace(0, 1.6, 65), np.linspace(0, 2 * np.pi, 96, endpoint=False), indexing="ij")
    r = 0.25 + 0.2 * np.sin(3.2 * h + 0.6) ** 2
    v = np.stack([r * np.cos(a), h, r * np.sin(a)], -1).reshape(-1, 3)
    quads = _grid_quads(96, 64, wrap_u=True)[:, ::-1] + 1
    lines = [f"v {p[0]:.6f} {p[1]:.6f} {p[2]:.6f}" for p in v] + [f"f {a} {b} {c} {d}" for a, b, c, d in quads]
    (folder / "vase.obj").write_text("\n".join(lines) + "\n")
    (folder / "scene.toml").write_text(SCENE.replace("{width}", str(width)).replace("{height}", str(height)))
    return folder / "scene.toml"


# --- timing -------------------------------------------------------------------------------------------


def _run(cmd: list[str]) -> float:
    t = time.perf_counter()
    r = subprocess.run(cmd, capture_output=True, text=True, env=ENV, cwd=REPO)
    elapsed = time.perf_counter() - t
    if r.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)} failed:\n{r.stderr[-2000:]}")
    return elapsed


def pair(a: list[str], b: list[str], repeat: int) -> dict:
    """A and B in turn after one untimed run of each: medians and the median of the pairs' ratios."""
    _run(a), _run(b)
    times = [(_run(a), _run(b)) for _ in range(repeat)]
    return {"warprt": statistics.median(t[0] for t in times), "mitsuba": statistics.median(t[1] for t in times),
            "ratio": statistics.median(t[0] / t[1] for t in times), "pairs": times}


# Where a cold process's time goes: each step a fresh process that does everything the step before did
# and one thing more, then leaves through os._exit as `warprt render` does (interpreter teardown apart).
LADDER = {
    "warprt": [("interpreter start", "import os; os._exit(0)"),
               ("+ import numpy", "import os, numpy; os._exit(0)"),
               ("+ import warp", "import os, warp; os._exit(0)"),
               ("+ warp.init()", "import os, warp; warp.config.quiet = True; warp.init(); os._exit(0)"),
               ("+ import warprt's renderer and CLI", "import os, warp; warp.config.quiet = True; warp.init(); "
                                                       "import warprt.cli, warprt.image, warprt.kernels; os._exit(0)")],
    "mitsuba": [("interpreter start", "import os; os._exit(0)"),
                ("+ import mitsuba", "import os, mitsuba; os._exit(0)"),
                ("+ set_variant('llvm_ad_rgb')", "import os, mitsuba; mitsuba.set_variant('llvm_ad_rgb'); os._exit(0)")],
}


def breakdown(repeat: int, out: Path) -> dict:
    """The cold default render taken apart: the LADDER's steps (medians of ``repeat`` runs), the render's
    own phases from `warprt render --stats`, and the modules that cost most to import (`python -X
    importtime`, self time, one run)."""
    ladder = {side: [(name, statistics.median(_run([sys.executable, "-c", code]) for _ in range(repeat)))
                     for name, code in steps] for side, steps in LADDER.items()}
    cmd = [sys.executable, "-X", "importtime", "-m", "warprt", "render", "--stats", "-o", str(out / "w.png")]
    runs = [subprocess.run(cmd, capture_output=True, text=True, env=ENV, cwd=REPO) for _ in range(repeat)]
    phases = {k: statistics.median(json.loads(r.stdout)["times"][k] for r in runs)
              for k in json.loads(runs[0].stdout)["times"]}
    imports = []
    for line in runs[-1].stderr.splitlines():
        if line.startswith("import time:") and "self" not in line:
            self_us, _, name = (x.strip() for x in line[len("import time:"):].split("|"))
            imports.append((int(self_us) / 1e6, name))
    return {"ladder": ladder, "phases": phases, "imports": sorted(imports, reverse=True)[:8]}


def run(repeat: int = 7) -> dict:
    out = Path(tempfile.mkdtemp())
    scene = write_mesh_scene(out / "meshes")
    warprt = [sys.executable, "-m", "warprt", "render", "-q", "-o", str(out / "w.png")]
    default = pair(warprt, [sys.executable, "-c", MITSUBA_COLD, "", str(out / "m.png")], repeat)
    print(f"cold default scene warprt/mitsuba {default['ratio']:.2f}", file=sys.stderr, flush=True)
    files = pair(warprt[:4] + [str(scene)] + warprt[4:], [sys.executable, "-c", MITSUBA_FILES, str(scene), str(out / "m.png")],
                 repeat)
    print(f"cold mesh files warprt/mitsuba {files['ratio']:.2f}", file=sys.stderr, flush=True)
    parts = breakdown(repeat, out)
    return {"default": default, "files": files, "breakdown": parts, "repeat": repeat, "size": [WIDTH, HEIGHT]}


def target_rows(data: dict) -> list[tuple[str, str, str]]:
    """The Targets table's rows: the cold ratios, target <= 1.0x."""
    d, f = data["default"], data["files"]
    w, h = data["size"]
    met = lambda ok: "met" if ok else "not met"
    return [
        ("Cold `warprt render` of the default scene (640x480): <= 1.0x Mitsuba's Python API, process start to PNG",
         f"{d['warprt']:.2f} s against {d['mitsuba']:.2f} s: {d['ratio']:.2f}x", met(d["ratio"] <= 1.0)),
        (f"Cold `warprt render` of five PLY/OBJ files ({w}x{h}): <= 1.0x a Mitsuba script reading them with its own "
         "`ply`/`obj` plugins", f"{f['warprt']:.2f} s against {f['mitsuba']:.2f} s: {f['ratio']:.2f}x", met(f["ratio"] <= 1.0)),
    ]


def report(data: dict) -> str:
    w, h = data["size"]
    lines = ["## Cold start", "",
             f"Process start to PNG file with every kernel cache warm, the two commands in turn ({data['repeat']} pairs after "
             "one untimed run each); seconds are medians, the ratio the median of the pairs' ratios. Default scene: `warprt "
             "render -o x.png` (640x480) against the scene through Mitsuba's Python API. Mesh files: `warprt render "
             f"scene.toml` ({w}x{h}; three binary PLY files, two OBJ, 92,672 triangles) against a script that loads the "
             "same files with Mitsuba's `ply` and `obj` shape plugins and renders them with the reference's Whitted "
             "integrator. Regenerate: `python -m benchmarks.cold`.", "",
             "| scene | warprt | Mitsuba | ratio |", "|---|---:|---:|---:|"]
    for key, name in (("default", "default scene"), ("files", "five PLY/OBJ files")):
        r = data[key]
        lines.append(f"| {name} | {r['warprt']:.2f} | {r['mitsuba']:.2f} | {r['ratio']:.2f} |")
    if "breakdown" in data:
        lines += ["", breakdown_report(data["breakdown"], data["default"])]
    return "\n".join(lines)


def breakdown_report(parts: dict, default: dict) -> str:
    lines = ["### Where the cold default render's time goes", "",
             "Each step is a fresh process doing what the step above did and one thing more, then leaving through "
             "`os._exit` as `warprt render` does; seconds are medians. The last row of each side is the whole command "
             "of the table above.", "", "| step | warprt | | step | Mitsuba |", "|---|---:|---|---|---:|"]
    w, m = parts["ladder"]["warprt"], parts["ladder"]["mitsuba"]
    w = w + [("+ load, build, trace, write (`warprt render`)", default["warprt"])]
    m = m + [("+ load the scene, render, write", default["mitsuba"])]
    seconds = lambda t: "" if t is None else f"{t:.3f}"
    for (a, ta), (b, tb) in itertools.zip_longest(w, m, fillvalue=("", None)):
        lines.append(f"| {a} | {seconds(ta)} | | {b} | {seconds(tb)} |")
    ph = parts["phases"]
    lines += ["", "The render's own phases (`warprt render --stats`, medians, seconds): "
              + ", ".join(f"{k} {v:.3f}" for k, v in ph.items()) + ".", "",
              "The most costly imports of that process (`python -X importtime`, self time): "
              + ", ".join(f"`{name}` {t * 1e3:.0f} ms" for t, name in parts["imports"]) + "."]
    return "\n".join(lines)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--repeat", type=int, default=7)
    ap.add_argument("--scene-only", metavar="FOLDER", help="write the mesh scene to FOLDER and stop")
    ap.add_argument("-o", "--output", default=str(ROOT / "results" / "cold.md"))
    args = ap.parse_args()
    if args.scene_only:
        print(write_mesh_scene(Path(args.scene_only)))
        return
    data = run(args.repeat)
    save(args.output, data, report(data))
    print(report(data))


if __name__ == "__main__":
    main()
