"""Grazing light shows no acne: a tessellated plane lit at 89 degrees from its normal (shadows on)
renders every lit pixel at the closed-form Phong value; a self-shadowed pixel would lose the
whole lit term."""

import numpy as np
import pytest

import warprt
from scenekit import make_scene
from oracle import camera_rays, face_normals, phong, rotation
from warprt.geometry import Geometry

from stability.probes import record

HALF = 4.0
ROTATE, CENTRE = [23.0, 37.0, 11.0], np.array([1.3, -0.7, 2.1])
MAT = {"ka": [0.2, 0.2, 0.2], "kd": [0.7, 0.6, 0.5], "ks": [0.5, 0.5, 0.5], "shininess": 8.0}
C_AMB, C_L = [0.1, 0.1, 0.1], [20.0, 20.0, 20.0]  # a bright light: the grazing term is ~0.24, not 0.01


N_CELLS = 16


def grid(n: int, half: float):
    """A square of side 2 half in y = 0 facing +y, as n x n quads split along their diagonals."""
    s = np.linspace(-half, half, n + 1)
    x, z = np.meshgrid(s, s, indexing="ij")
    vertices = np.stack([x, np.zeros_like(x), z], -1).reshape(-1, 3)
    i = np.arange(n)[:, None] * (n + 1) + np.arange(n)[None, :]
    a, b, c, d = i, i + 1, i + n + 2, i + n + 1
    faces = np.concatenate([np.stack([a, b, c], -1).reshape(-1, 3), np.stack([a, c, d], -1).reshape(-1, 3)])
    return vertices, faces


def float32_normals(scene, vertices, faces):
    """Unit normals of the triangles the renderer holds (float32, camera-relative), in float64.
    At 89 degrees n.L moves one for one with the normal's tilt, so the closed form is evaluated
    on these triangles, not on the exact plane their float32 vertices approximate."""
    points = Geometry(scene).points_np[: len(vertices)].astype(np.float64)
    return face_normals(points[faces])


def triangle_at(u, w):
    """The grid triangle under plane coordinates (u, w), and the distance to its nearest edge in cells."""
    h = 2 * HALF / N_CELLS
    fu, fw = (u + HALF) / h, (w + HALF) / h
    i, j = np.clip(np.floor(fu).astype(int), 0, N_CELLS - 1), np.clip(np.floor(fw).astype(int), 0, N_CELLS - 1)
    fu, fw = fu - i, fw - j
    upper = fw >= fu  # triangle (a, b, c) of the cell; (a, c, d) below its diagonal
    face = np.where(upper, i * N_CELLS + j, N_CELLS * N_CELLS + i * N_CELLS + j)
    margin = np.minimum.reduce([fu, fw, 1 - fu, 1 - fw, np.abs(fw - fu) / np.sqrt(2)])
    return face, margin


@pytest.mark.parametrize("angle", [89.0, 89.9])
@pytest.mark.parametrize("distance", [9.0, 300.0], ids=["camera 9 away", "camera 300 away"])
def test_grazing_light_has_no_acne(angle, distance):
    vertices, faces = grid(N_CELLS, HALF)  # 512 triangles: shadow rays skim over many shared edges
    R = rotation(ROTATE)
    n0, t1, t2 = R @ [0, 1, 0], R @ [1, 0, 0], R @ [0, 0, 1]
    eye = CENTRE + distance * (np.cos(np.radians(30)) * n0 + np.sin(np.radians(30)) * t1)
    a = np.radians(angle)
    light = CENTRE + 200.0 * (np.cos(a) * n0 + np.sin(a) * (-t2))
    fovy = 2 * np.degrees(np.arctan(HALF * 0.9 / distance))
    plane = {"shape": "triangles", "vertices": vertices.tolist(), "faces": faces.tolist(), "material": "m",
             "rotate": ROTATE, "translate": CENTRE.tolist()}
    camera = {"eye": eye.tolist(), "center": CENTRE.tolist(), "up": n0.tolist(), "fovy": fovy, "width": 96, "height": 72}
    scene = make_scene([plane], {"m": MAT}, [{"position": light.tolist(), "color": C_L}], camera=camera, ambient=C_AMB)
    image, stats = warprt.render(scene, threads=2)
    assert stats.rays["shadow"] > 0

    o, d = camera_rays(scene.camera)
    t = ((CENTRE - o) @ n0) / (d @ n0)
    p = o + t[..., None] * d
    u, w = (p - CENTRE) @ t1, (p - CENTRE) @ t2
    inside = (np.abs(u) < HALF * 0.999) & (np.abs(w) < HALF * 0.999)
    towards_eye = np.sign((eye - CENTRE) @ n0)
    # Acne: a lit pixel that lost (half of) its lit term to a shadow ray that hit its own surface.
    n = np.broadcast_to(n0 * towards_eye, p.shape)
    expect = phong(p, n, -d, [(light, C_L)], MAT, C_AMB)
    n_dot_l = np.sum(n * (light - p) / np.linalg.norm(light - p, axis=-1, keepdims=True), -1)
    lit = inside & (n_dot_l > 0)
    dark = (expect - image).max(-1)[lit] > 0.5 * np.asarray(MAT["kd"]).min() * C_L[0] * n_dot_l[lit].min()
    # Equality: the closed form on the float32 triangle under each pixel (away from its edges).
    face, margin = triangle_at(u, w)
    n32 = float32_normals(scene, vertices, faces)[face]
    n32 *= np.sign(np.sum(n32 * n, -1))[..., None]
    exact = phong(p, n32, -d, [(light, C_L)], MAT, C_AMB)
    clear = lit & (margin > 1e-3)
    error = np.abs(image - exact).max(-1)[clear]
    record(f"grazing/{angle:g} deg/{distance:g} away", {
        "lit_pixels": int(lit.sum()), "acne_pixels": int(dark.sum()), "compared_pixels": int(clear.sum()),
        "max_abs_error": float(error.max()), "max_abs_error_vs_exact_plane": float(np.abs(image - expect).max(-1)[lit].max()),
        "n_dot_l": [float(n_dot_l[lit].min()), float(n_dot_l[lit].max())]})
    assert lit.sum() > 0.6 * lit.size  # the plane fills most of the view
    assert dark.sum() == 0
    assert clear.sum() > 0.9 * lit.sum()
    np.testing.assert_allclose(image[clear], exact[clear], rtol=1e-4, atol=1e-5)
