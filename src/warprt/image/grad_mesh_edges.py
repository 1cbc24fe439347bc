"""The meshes' edges and the faces they join, for the boundary term (backward(edges=True)): which edges
are silhouettes from a viewpoint (the eye, a light, a mirror's virtual eye) and which the camera sees jump
(camera_edges), the one table the camera's edges and the shadows' occluders are both read from."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..scene import drawn_objects, position_ids

COPLANAR = 1e-6  # |n1 x n2| of two flat faces' unit normals below which their shared edge shows no crease


@dataclass
class MeshEdges:
    """Each edge of the drawn objects once, welded by vertex position per object as the vertex normals are
    (scene.position_ids), sorted by (object, position): its first face's two vertex indices ``v``, its first
    two faces ``f1`` and ``f2`` (f2 = f1 for an open edge), how many faces share it (``count``) and face
    f2's copies of v (``v2``, matched by position). Edges whose two ends share a position are left out."""

    v: np.ndarray
    v2: np.ndarray
    f1: np.ndarray
    f2: np.ndarray
    count: np.ndarray

    @property
    def pair(self) -> np.ndarray:
        """Whether each edge joins exactly two faces."""
        return self.count == 2


def mesh_edges(scene, geom) -> MeshEdges:
    """The MeshEdges of ``geom``'s triangles (the drawn objects of ``scene``, in order)."""
    faces = geom.indices_np.reshape(-1, 3).astype(np.int64)
    pos, unique = [], 0
    for obj in drawn_objects(scene):  # one id per position and object
        ids = position_ids(obj.vertices) if len(obj.vertices) else np.zeros(0, np.int64)
        pos.append(ids + unique)
        unique += int(ids.max()) + 1 if len(ids) else 0
    pos = np.concatenate(pos) if pos else np.zeros(0, np.int64)
    ev = faces[:, [[0, 1], [1, 2], [2, 0]]].reshape(-1, 2)
    ef = np.repeat(np.arange(len(faces)), 3)
    lo, hi = np.minimum(pos[ev[:, 0]], pos[ev[:, 1]]), np.maximum(pos[ev[:, 0]], pos[ev[:, 1]])
    order = np.lexsort((ef, hi, lo))
    lo, hi, ev, ef = lo[order], hi[order], ev[order], ef[order]
    start = np.flatnonzero(np.r_[True, (lo[1:] != lo[:-1]) | (hi[1:] != hi[:-1])]) if len(lo) else np.zeros(0, int)
    count = np.diff(np.r_[start, len(lo)])
    start, count = start[lo[start] != hi[start]], count[lo[start] != hi[start]]
    i, k = start, np.where(count >= 2, start + 1, start)  # a pair's two faces
    same = pos[ev[k, 0]] == pos[ev[i, 0]]
    v2 = np.stack([np.where(same, ev[k, 0], ev[k, 1]), np.where(same, ev[k, 1], ev[k, 0])], axis=1)
    return MeshEdges(ev[i], v2, ef[i], ef[k], count)


def face_normals(p: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Per face its unit normal by its winding (0 where degenerate)."""
    tri = p[faces]
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    length = np.linalg.norm(n, axis=1, keepdims=True)
    return np.divide(n, length, out=np.zeros_like(n), where=length > 0)


def facing(normal: np.ndarray, corner: np.ndarray, at: np.ndarray, directional: bool = False) -> np.ndarray:
    """Per face (unit ``normal``, a ``corner`` of it) whether it faces the point ``at``, or with
    ``directional`` the light travelling along ``at`` (its winding's normal towards it)."""
    if directional:
        return normal @ np.asarray(at, np.float64) < 0.0
    return np.einsum("ij,ij->i", normal, corner - at) < 0.0


def silhouettes(m: MeshEdges, front: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(which, vertices): whether each edge is a silhouette from a viewpoint whose faces ``front`` faces (open,
    shared by more than two faces, or joining a face that faces it and one that does not), and its two
    vertex indices as the face that faces it has them (its first face's otherwise)."""
    which = ~m.pair | (front[m.f1] != front[m.f2])
    second = m.pair & ~front[m.f1] & front[m.f2]
    return which, np.where(second[:, None], m.v2, m.v)


def _same(a: np.ndarray, i: np.ndarray, k: np.ndarray) -> np.ndarray:
    """Whether a per-vertex attribute is equal at vertices i and k (rows)."""
    return np.all(a[i] == a[k], axis=-1)


def camera_edges(scene, geom, fx, eye, sources=None, m: MeshEdges | None = None, rows: bool = False):
    """(E, 2) vertex indices of the edges whose image can jump, sorted by (object, position): of each mesh's
    edges (mesh_edges, or ``m``), those that are open (one face), silhouettes from ``eye`` (two faces facing
    opposite ways from it), shared by more than two faces, or creases where the shading jumps (two faces of
    other materials, a flat pair not coplanar, a smooth pair whose normals, uvs or colours differ at the
    edge, or with shadows (``sources``: ShadowSources) a smooth pair one of whose faces faces a source and
    the other does not: there the mesh shadows itself); each by its face facing the eye (the edge the
    visible side shows), else its first. With ``rows`` also their rows of ``m`` and per face whether it faces the
    eye (for rims)."""
    if geom.triangle_count == 0:
        none = np.zeros((0, 2), np.int64)
        return (none, np.zeros(0, np.int64), np.zeros(0, bool)) if rows else none
    m = mesh_edges(scene, geom) if m is None else m
    p = geom.points_np.astype(np.float64)
    faces = geom.indices_np.reshape(-1, 3).astype(np.int64)
    normal = face_normals(p, faces)
    front = facing(normal, p[faces[:, 0]], np.asarray(eye, np.float64))
    f1, f2, (i0, i1), (a2, b2) = m.f1, m.f2, m.v.T, m.v2.T
    jump = (front[f1] != front[f2]) | (geom.tri_material_np[f1] != geom.tri_material_np[f2])
    smooth = (geom.tri_smooth_np[f1] != 0) & (geom.tri_smooth_np[f2] != 0)
    flat = (geom.tri_smooth_np[f1] == 0) & (geom.tri_smooth_np[f2] == 0)
    crease = np.linalg.norm(np.cross(normal[f1], normal[f2]), axis=1) > COPLANAR
    smooth_jump = ~(_same(geom.normals.numpy(), i0, a2) & _same(geom.normals.numpy(), i1, b2))
    jump |= ~(smooth | flat) | (flat & crease) | (smooth & smooth_jump)
    for table in ([geom.uv_array().numpy()] if fx.texture else []) + ([geom.colors.numpy()] if fx.vertex_color else []):
        jump |= ~(_same(table, i0, a2) & _same(table, i1, b2))
    for at, directional in zip(sources.at, sources.directional) if sources is not None else ():
        lit = facing(normal, p[faces[:, 0]], at, directional)
        jump |= smooth & (lit[f1] != lit[f2])
    keep = ~m.pair | jump
    use_second = m.pair & ~front[f1] & front[f2]
    edges = np.where(use_second[:, None], m.v2, m.v)[keep]
    return (edges, np.flatnonzero(keep), front) if rows else edges


def rims(geom, m: MeshEdges, rows: np.ndarray, front: np.ndarray, curved: np.ndarray) -> np.ndarray:
    """Per edge (``rows`` of ``m``) whether it is a rim of a curved mirror seen from the eye whose faces ``front``
    faces (camera_edges'): a silhouette whose
    face towards the eye is smooth and one ``curved`` marks (grad_glass_edges.crossed_surfaces), where the
    reflection its jump reads turns fast along it (at grazing incidence the interpolated normal sweeps what it
    reflects), so that one Gauss point a piece misreads the integral (grad_edge_points.FINE_POINTS)."""
    if not len(rows) or not curved.any():
        return np.zeros(len(rows), bool)
    f1, f2 = m.f1[rows], m.f2[rows]
    near = np.where(front[f1], f1, f2)
    return m.pair[rows] & (front[f1] != front[f2]) & (geom.tri_smooth_np[near] != 0) & curved[near]
