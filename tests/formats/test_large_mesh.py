"""A 2-million-triangle mesh renders through the real command, and its memory is reported.

Measured once on the 2-core, 24 GiB machine: a 2M-triangle PLY heightfield rendered at 640x480
peaks at 0.92 GiB resident (the same from OBJ), of which 0.31 GB are the geometry arrays and BVH.
This test keeps the image small and the mesh flat-shaded (no vertex normals) to stay near 10 s;
its bound on the peak is loose on purpose: it catches a copy too many, not a few megabytes.
"""

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np

from marks import slow
from scenekit import write_scene

SRC = str(Path(__file__).resolve().parents[2] / "src")
N = 1000  # N x N quads: 2,000,000 triangles


def write_heightfield_ply(path: Path, n: int) -> int:
    """A wavy n x n grid of quads over [-1, 1]^2 as binary PLY, two triangles per quad."""
    x, z = np.meshgrid(np.linspace(-1, 1, n + 1), np.linspace(-1, 1, n + 1))
    y = 0.1 * np.sin(6 * x) * np.cos(5 * z)
    v = np.stack([x, y, z], -1).reshape(-1, 3).astype("<f4")
    i = np.arange((n + 1) * (n + 1)).reshape(n + 1, n + 1)
    a, b, c, d = i[:-1, :-1], i[:-1, 1:], i[1:, 1:], i[1:, :-1]
    f = np.concatenate([np.stack([a, d, c], -1).reshape(-1, 3), np.stack([a, c, b], -1).reshape(-1, 3)])
    rec = np.empty(len(f), dtype=[("n", "u1"), ("i", "<i4", 3)])
    rec["n"], rec["i"] = 3, f
    header = (f"ply\nformat binary_little_endian 1.0\nelement vertex {len(v)}\nproperty float x\nproperty float y\n"
              f"property float z\nelement face {len(f)}\nproperty list uchar int vertex_indices\nend_header\n")
    with open(path, "wb") as out:
        out.write(header.encode())
        out.write(v.tobytes())
        out.write(rec.tobytes())
    return len(f)


@slow
def test_two_million_triangles_render_and_report_memory(tmp_path):
    n_tri = write_heightfield_ply(tmp_path / "field.ply", N)
    write_scene(tmp_path, {"camera": {"eye": [0.0, 2.0, 2.5], "center": [0.0, 0.0, 0.0], "width": 64, "height": 48},
                           "lights": [{"position": [2.0, 4.0, 3.0]}], "objects": [{"mesh": "field.ply"}]}, "s.toml")
    env = {**os.environ, "PYTHONPATH": SRC + os.pathsep + os.environ.get("PYTHONPATH", "")}
    r = subprocess.run([sys.executable, "-m", "warprt", "render", "s.toml", "-o", "f.png", "-q", "--stats-file", "st.json"],
                       cwd=tmp_path, env=env, capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr
    stats = json.loads((tmp_path / "st.json").read_text())
    assert stats["triangles"] == n_tri == 2 * N * N
    mem = stats["memory"]
    assert mem["geometry"]["indices"] == 12 * n_tri  # 3 int32 indices per triangle
    assert mem["geometry"]["total"] >= 12 * n_tri + 12 * (N + 1) ** 2
    assert mem["peak_rss"] < 3 * 2**30
    from warprt.image import read_image

    image = read_image(tmp_path / "f.png")
    assert image.shape == (48, 64, 3)
    assert (image.max(-1) > 0.05).mean() > 0.3  # the field fills much of the view, lit
