"""Vertex normals for smooth shading, in NumPy float64 (no Warp, so the Mitsuba reference and the
readers share them): smoothed over a whole mesh, split at a crease angle or by OBJ smoothing groups,
or the file's own; ``smooth = true | false | "auto" | <degrees>`` picks one (resolve_normals).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

AUTO_CREASE_DEGREES = 30.0  # "auto" on a mesh without normals of its own (Blender's auto smooth default)


def position_ids(vertices: np.ndarray) -> np.ndarray:
    """One id per distinct position: vertices a file duplicates (uv seams) share one."""
    # Positions compared as raw bytes (much faster than np.unique(axis=0)); + 0.0 makes -0.0 equal 0.0.
    keys = np.ascontiguousarray(vertices + 0.0, np.float64).view(np.dtype((np.void, 24))).ravel()
    _, inverse = np.unique(keys, return_inverse=True)
    return inverse.reshape(-1)


def face_normals_and_angles(vertices: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Unit face normals (M, 3) (zero for a degenerate face) and each corner's angle (M, 3)."""
    p = vertices[faces]
    fn = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    length = np.linalg.norm(fn, axis=1, keepdims=True)
    fn = np.divide(fn, length, out=np.zeros_like(fn), where=length > 0)
    angle = np.zeros(faces.shape)
    for k in range(3):
        e1 = p[:, (k + 1) % 3] - p[:, k]
        e2 = p[:, (k + 2) % 3] - p[:, k]
        n1, n2 = np.linalg.norm(e1, axis=1), np.linalg.norm(e2, axis=1)
        cos = np.einsum("ij,ij->i", e1, e2) / np.maximum(n1 * n2, 1e-300)
        angle[:, k] = np.arccos(np.clip(cos, -1.0, 1.0))
    return fn, angle


def vertex_normals(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Angle-weighted vertex normals (float64), shared by vertices at the same position so that
    a mesh with split seams (OBJ texture seams) still shades smoothly across them."""
    inverse = position_ids(vertices)
    n_unique = int(inverse.max()) + 1 if len(inverse) else 0
    fn, angle = face_normals_and_angles(vertices, faces)
    acc = np.zeros((n_unique, 3))
    for k in range(3):
        target = inverse[faces[:, k]]
        for axis in range(3):
            acc[:, axis] += np.bincount(target, weights=fn[:, axis] * angle[:, k], minlength=n_unique)
    length = np.linalg.norm(acc, axis=1, keepdims=True)
    acc = np.divide(acc, length, out=np.zeros_like(acc), where=length > 0)
    return acc[inverse]


def _components(n: int, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Connected components of n nodes joined by the pairs (a[i], b[i]): each node's smallest member.
    Hooking to the smaller root, then pointer jumping, until no pair spans two components."""
    label = np.arange(n)
    while len(a):
        la, lb = label[a], label[b]
        apart = la != lb
        if not apart.any():
            break
        np.minimum.at(label, np.maximum(la, lb)[apart], np.minimum(la, lb)[apart])
        while True:
            jumped = label[label]
            if np.array_equal(jumped, label):
                break
            label = jumped
    return label


def corner_normals(vertices: np.ndarray, faces: np.ndarray, crease_degrees: float | None = AUTO_CREASE_DEGREES,
                   smoothing_group: np.ndarray | None = None) -> np.ndarray:
    """Per-corner normals (M, 3, 3), as Blender's auto smooth and edge split make them: two triangles
    sharing an edge shade smoothly across it when their face normals differ by at most
    ``crease_degrees`` (None: any angle) and, where ``smoothing_group`` is given (OBJ 's', one value
    per face, 0 = flat), they are in the same non-zero group. A corner's normal is the angle-weighted
    sum of the face normals of the corners around its vertex it is so connected to. Vertices are
    matched by position (a uv seam is not a crease); an edge of three or more triangles is a crease."""
    faces = np.asarray(faces, np.int64)
    m = len(faces)
    pid = position_ids(vertices)[faces]
    fn, angle = face_normals_and_angles(vertices, faces)
    # Half-edges (face f, corner k) -> (k, k + 1), paired with the opposite half-edge by position.
    f_of = np.repeat(np.arange(m), 3)
    k_of = np.tile(np.arange(3), m)
    a, b = pid[f_of, k_of], pid[f_of, (k_of + 1) % 3]
    key = np.minimum(a, b) * (int(pid.max(initial=0)) + 1) + np.maximum(a, b)
    order = np.argsort(key, kind="stable")
    sorted_key = key[order]
    start = np.r_[0, np.nonzero(np.diff(sorted_key))[0] + 1]
    count = np.diff(np.r_[start, len(sorted_key)])
    pair = start[count == 2]
    h1, h2 = order[pair], order[pair + 1]
    f1, f2 = f_of[h1], f_of[h2]
    smooth = np.ones(len(f1), bool)
    if crease_degrees is not None:
        smooth &= np.einsum("ij,ij->i", fn[f1], fn[f2]) >= np.cos(np.radians(crease_degrees)) - 1e-12
    if smoothing_group is not None:
        g = np.asarray(smoothing_group, np.int64)
        smooth &= (g[f1] == g[f2]) & (g[f1] != 0)
    h1, f1, f2 = h1[smooth], f1[smooth], f2[smooth]
    # Join the two faces' corners at each end of the shared edge.
    ends = (a[h1], b[h1])
    corner_of = lambda f, p: f * 3 + np.argmax(pid[f] == p[:, None], axis=1)
    ja = np.concatenate([corner_of(f1, p) for p in ends])
    jb = np.concatenate([corner_of(f2, p) for p in ends])
    cluster = _components(3 * m, ja, jb)
    weighted = (fn[:, None, :] * angle[:, :, None]).reshape(-1, 3)
    acc = np.stack([np.bincount(cluster, weights=weighted[:, ax], minlength=3 * m) for ax in range(3)], 1)
    n = acc[cluster]
    length = np.linalg.norm(n, axis=1, keepdims=True)
    return np.divide(n, length, out=np.zeros_like(n), where=length > 0).reshape(m, 3, 3)


def weld_corner_normals(faces: np.ndarray, normals: np.ndarray):
    """Per-corner normals (M, 3, 3) to per-vertex ones: a vertex whose corners carry different normals
    is split. Returns (keep: which old vertex each new one is, new faces, normals per new vertex)."""
    vertex = np.asarray(faces, np.int64).reshape(-1)
    n = np.ascontiguousarray(normals, np.float64).reshape(-1, 3) + 0.0  # -0.0 == 0.0
    # Sorted by vertex, then normal (exact comparisons: a lexicographic sort, not a hash).
    order = np.lexsort((n[:, 2], n[:, 1], n[:, 0], vertex))
    sv, sn = vertex[order], n[order]
    first_of_run = np.r_[True, (sv[1:] != sv[:-1]) | (sn[1:] != sn[:-1]).any(1)] if len(order) else np.zeros(0, bool)
    inverse = np.empty(len(order), np.int64)
    inverse[order] = np.cumsum(first_of_run) - 1
    first = order[first_of_run]
    return vertex[first], inverse.reshape(-1, 3), n[first]


@dataclass
class Shading:
    """What resolve_normals decided for one mesh: ``keep`` (None: the vertices as they are) selects
    the new vertices from the old, ``faces`` index the new ones, ``normals`` are per new vertex (None:
    computed from the triangles downstream, or flat), ``smooth`` whether normals are interpolated."""

    keep: np.ndarray | None
    faces: np.ndarray
    normals: np.ndarray | None
    smooth: bool

    def take(self, a: np.ndarray | None) -> np.ndarray | None:
        """A per-vertex array (positions, uv, colours) for the new vertices."""
        return a if a is None or self.keep is None else np.ascontiguousarray(a[self.keep])


def resolve_normals(vertices, faces, smooth, file_normals=None, smoothing_group=None,
                    auto_crease: float = AUTO_CREASE_DEGREES) -> Shading:
    """The normals a mesh is shaded with. ``smooth``: False, flat faces; True, every vertex smoothed
    over its triangles (vertex_normals); "auto", the file's own normals (``file_normals``, per corner
    (M, 3, 3)) where it has them, else its OBJ smoothing groups, else a crease at ``auto_crease``
    degrees; a number, a crease at that angle whatever the file says."""
    if smooth is False or smooth is True:
        return Shading(None, faces, None, bool(smooth))
    if smooth == "auto":
        if file_normals is not None:
            n = np.asarray(file_normals, np.float64)
            length = np.linalg.norm(n, axis=-1, keepdims=True)
            # A zero normal cannot be normalised: the face's own there.
            fn, _ = face_normals_and_angles(vertices, faces)
            n = np.where(length > 0, n / np.where(length > 0, length, 1.0), fn[:, None, :])
            return Shading(*weld_corner_normals(faces, n), True)
        if smoothing_group is not None:
            if not np.any(smoothing_group):
                return Shading(None, faces, None, False)  # 's off' throughout: the file says flat
            return Shading(*weld_corner_normals(faces, corner_normals(vertices, faces, None, smoothing_group)), True)
        crease = auto_crease
    else:
        crease = float(smooth)
    return Shading(*weld_corner_normals(faces, corner_normals(vertices, faces, crease)), True)
