"""Seams do not leak: a ray aimed exactly at the diagonal two triangles of a quad share hits it."""

import numpy as np

import warprt
from scenekit import make_scene
from warprt.geometry import Geometry

from stability.probes import cast, record

# The quad x, y in [-5, 5] at z = 0, split along its diagonal from (-5, -5) to (5, 5).
QUAD = {"shape": "triangles", "vertices": [[-5, -5, 0], [5, -5, 0], [5, 5, 0], [-5, 5, 0]],
        "faces": [[0, 1, 2], [0, 2, 3]], "material": "m"}
EYE = [0.0, 0.0, 10.0]  # the rays' origin: eye_offset(EYE) in the BVH's coordinates, as the renderer's
CAMERA = {"eye": EYE, "center": [0.0, 0.0, 0.0], "up": [0.0, 1.0, 0.0], "fovy": 40.0, "width": 101, "height": 101}


def quad_geometry():
    return Geometry(make_scene([QUAD], {"m": {"ka": [1.0] * 3, "kd": [0.0] * 3}}, camera=CAMERA, ambient=[1.0] * 3))


def test_the_issue_ray_hits_the_diagonal():
    d = np.array([[0.30458447, 0.30458447, -0.9024725]])
    geom = quad_geometry()  # keep it alive: the mesh is freed with it
    t, face = cast(geom.mesh.id, geom.eye_offset(EYE)[None].astype(np.float64), d)
    p = np.asarray(EYE) + t[0] * d[0] / np.linalg.norm(d[0])
    record("seams/issue_ray", {"face": int(face[0]), "t": float(t[0]), "hit": p.tolist()})
    assert face[0] in (0, 1)
    # It crosses z = 0 at x = y = 10 * 0.30458447 / 0.9024725 = 3.375..., on the diagonal.
    np.testing.assert_allclose(p, [10 * 0.30458447 / 0.9024725] * 2 + [0.0], atol=1e-5)


def test_rays_along_the_whole_diagonal_hit():
    """100,000 rays from the eye to float32 points exactly on the diagonal x = y."""
    s = np.linspace(-4.9999, 4.9999, 100_000, dtype=np.float32).astype(np.float64)
    target = np.stack([s, s, np.zeros_like(s)], 1) - EYE
    geom = quad_geometry()
    origins = np.broadcast_to(geom.eye_offset(EYE).astype(np.float64), target.shape)
    t, face = cast(geom.mesh.id, origins, target / np.linalg.norm(target, axis=1, keepdims=True))
    record("seams/diagonal_rays", {"rays": len(s), "missed": int((face < 0).sum())})
    assert (face >= 0).all()


def test_rendered_diagonal_has_no_gap():
    """Looking straight down at the quad with a square image, pixel (x, y) and (y, x) rays are
    mirror images: those with x = y run exactly over the diagonal. Every pixel sees the quad."""
    scene = make_scene([QUAD], {"m": {"ka": [1.0] * 3, "kd": [0.0] * 3}}, camera=CAMERA, ambient=[1.0] * 3)
    image, _ = warprt.render(scene, threads=2)
    hit = image[..., 0] == 1.0
    diagonal = hit[::-1].diagonal()  # rows are counted from the top, the seed's y from the bottom
    record("seams/render", {"pixels": int(hit.size), "missed": int((~hit).sum()), "diagonal_pixels": len(diagonal)})
    assert diagonal.all() and hit.all()
