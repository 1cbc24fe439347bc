"""Deep or crowded BVHs lose no hits. Warp's traversal stack holds 32 entries and gives up when it
is full; its builders (SAH, median; LBVH falls back to SAH on the CPU) stop splitting at depth 31,
so a traversal, which pushes at most one node per level, never fills it. Checked against a
float64 nearest-hit oracle on geometry that would build far deeper trees: a 40-level chain of
nested triangles and a million triangles, half of them packed in an exponential cluster."""

import numpy as np
import pytest

from marks import slow
from oracle import ray_triangle
from warprt.geometry import Geometry

from stability.probes import cast, mesh_scene, record


def nearest(o, d, tri, candidates):
    """The float64 ray-triangle test over the candidate triangles of one ray: (t, margin) of the nearest."""
    h = ray_triangle(o, d, tri[candidates, 0], tri[candidates, 1], tri[candidates, 2])
    if not h.hit.any():
        return np.inf, np.abs(h.margin).min() if len(h.margin) else np.inf
    k = np.argmin(np.where(h.hit, h.t, np.inf))
    return h.t[k], np.abs(h.margin[np.isfinite(h.t) & (h.t > 0)]).min()


def compare(name, vertices, faces, origins, dirs, constructor):
    tri = vertices[faces]
    dirs = dirs / np.linalg.norm(dirs, axis=1, keepdims=True)
    # The BVH over the coordinates as given (origin 0): the rays and the brute force are in them.
    geom = Geometry(mesh_scene({name: (vertices, faces)}, eye=[0.0, 0.0, 0.0], center=[0.0, 0.0, -1.0]),
                    bvh_constructor=constructor, origin=np.zeros(3))
    t, face = cast(geom.mesh.id, origins, dirs)
    centre = tri.mean(axis=1)
    radius2 = (((tri - centre[:, None]) ** 2).sum(axis=2).max(axis=1)) * 1.001
    lost = wrong = compared = 0
    for i, (o, d) in enumerate(zip(origins.astype(np.float64), dirs.astype(np.float64))):
        w = centre - o  # candidates: triangles whose bounding sphere the ray's line passes through
        along = w @ d
        off2 = np.einsum("ij,ij->i", w, w) - along * along
        t_true, margin = nearest(o, d, tri, np.nonzero(off2 <= radius2)[0])
        if margin < 1e-5:  # too close to an edge for float32 and float64 to agree on the face
            continue
        compared += 1
        if np.isfinite(t_true) and face[i] < 0:
            lost += 1
        elif np.isfinite(t_true) and abs(t[i] - t_true) > 1e-5 * t_true:
            wrong += 1
    return {"rays": len(origins), "compared": compared, "lost_hits": lost, "farther_hits": wrong}


@pytest.mark.parametrize("constructor", ["sah", "median"])
def test_a_40_level_chain_of_nested_triangles(constructor):
    """Triangle k sits at 2^(30-k) along an axis, 2^(29-k) across: split by split the builders peel
    one triangle off, a chain 40 deep. Rays start at the chain's tip, so the nearest hit is the
    deepest triangle and every level's sibling is pushed on the way down."""
    rng = np.random.default_rng(3)
    axis = np.array([1.0, 1.0, 1.0]) / np.sqrt(3.0)
    a = np.array([1.0, -1.0, 0.0]) / np.sqrt(2.0)
    b = np.cross(axis, a)
    k = np.arange(40)
    size, at = 2.0 ** (29 - k), 2.0 ** (30 - k)
    corners = [a, -0.5 * a + 0.87 * b, -0.5 * a - 0.87 * b]
    vertices = np.concatenate([[axis * at[i] + size[i] * c for c in corners] for i in k])
    faces = np.arange(3 * len(k)).reshape(-1, 3)
    dirs = axis + rng.normal(size=(400, 3)) * 0.05
    figures = compare("chain", vertices, faces, np.zeros((400, 3)), dirs, constructor)
    record(f"bvh_depth/chain 40/{constructor}", figures)
    assert figures["compared"] > 300
    assert figures["lost_hits"] == 0 and figures["farther_hits"] == 0


@slow
@pytest.mark.parametrize("constructor", ["sah"])  # the renderer's; median is covered by the chain
def test_a_million_triangles_half_in_an_exponential_cluster(constructor):
    rng = np.random.default_rng(4)
    n = 500_000
    soup = rng.uniform(-50, 50, (n, 1, 3)) + rng.normal(size=(n, 3, 3)) * 0.3
    # The cluster: triangles whose size and distance from a point both fall as 2^-x, x up to 30.
    x = rng.uniform(0, 30, n)
    scale = 2.0 ** -x
    cluster = [5.0, -3.0, 2.0] + rng.normal(size=(n, 1, 3)) * scale[:, None, None] + rng.normal(size=(n, 3, 3)) * 0.5 * scale[:, None, None]
    vertices = np.concatenate([soup, cluster]).reshape(-1, 3)
    faces = np.arange(len(vertices)).reshape(-1, 3)
    # Rays from outside towards random soup triangles and into the cluster.
    origins = rng.uniform(-80, 80, (80, 3))
    targets = np.concatenate([soup[rng.integers(0, n, 40)].mean(axis=1),
                              cluster[rng.integers(0, n, 40)].mean(axis=1)])
    figures = compare("million", vertices, faces, origins, targets - origins, constructor)
    record(f"bvh_depth/1e6 triangles/{constructor}", figures | {"triangles": len(faces)})
    assert figures["compared"] > 50
    assert figures["lost_hits"] == 0 and figures["farther_hits"] == 0
