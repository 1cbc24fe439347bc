"""Procedural shapes a scene file can name with ``shape = "..."``.

Each builder returns float64 vertices (N, 3) and int64 faces (M, 3), counter-clockwise seen from
outside, in the object's own space (centred at the origin; the plane lies in y = 0 facing +y).
Where a textured material needs them, WITH_UV builds the same triangles with texture coordinates.
"""

from __future__ import annotations

import numpy as np

from ..errors import show
from .toml_fields import TableReader, did_you_mean

# Built here in NumPy rather than with trimesh.creation: importing trimesh costs about 0.6 s,
# which a scene made of built-in shapes should not pay at every start.


def sphere(radius: float = 1.0, subdivisions: int = 3):
    """An icosphere: the icosahedron with each triangle split in four, subdivisions times,
    vertices pushed onto the sphere; 20 * 4**subdivisions near-equal triangles."""
    t = (1.0 + 5.0**0.5) / 2.0
    v = np.array([[-1, t, 0], [1, t, 0], [-1, -t, 0], [1, -t, 0], [0, -1, t], [0, 1, t],
                  [0, -1, -t], [0, 1, -t], [t, 0, -1], [t, 0, 1], [-t, 0, -1], [-t, 0, 1]], np.float64)
    f = np.array([[0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11], [1, 5, 9], [5, 11, 4],
                  [11, 10, 2], [10, 7, 6], [7, 1, 8], [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8],
                  [3, 8, 9], [4, 9, 5], [2, 4, 11], [6, 2, 10], [8, 6, 7], [9, 8, 1]], np.int64)
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    for _ in range(subdivisions):
        # One new vertex per unique edge, shared by the two faces on either side of it.
        edges = np.sort(np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]]), axis=1)
        unique, inverse = np.unique(edges, axis=0, return_inverse=True)
        mid = v[unique].mean(axis=1)
        mid /= np.linalg.norm(mid, axis=1, keepdims=True)
        m = inverse.reshape(3, -1) + len(v)  # midpoints of edges (0,1), (1,2), (2,0) of each face
        a, b, c = f[:, 0], f[:, 1], f[:, 2]
        f = np.concatenate([np.stack([a, m[0], m[2]], 1), np.stack([b, m[1], m[0]], 1),
                            np.stack([c, m[2], m[1]], 1), np.stack([m[0], m[1], m[2]], 1)])
        v = np.vstack([v, mid])
    return v * radius, f


def uv_sphere(radius: float = 1.0, segments=(32, 64)):
    """A latitude-longitude sphere with exactly shared seam and pole vertices."""
    rings, sectors = int(segments[0]), int(segments[1])
    theta = np.linspace(0.0, np.pi, rings + 1)[1:-1]
    phi = np.arange(sectors) * (2.0 * np.pi / sectors)
    t, p = np.meshgrid(theta, phi, indexing="ij")
    ring_v = np.stack([np.sin(t) * np.cos(p), np.cos(t), -np.sin(t) * np.sin(p)], -1).reshape(-1, 3)
    v = np.vstack([[0.0, 1.0, 0.0], ring_v, [0.0, -1.0, 0.0]]) * radius
    south = len(v) - 1

    def idx(r, s):
        return 1 + r * sectors + (s % sectors)

    faces = []
    for s in range(sectors):
        faces.append((0, idx(0, s), idx(0, s + 1)))
        faces.append((south, idx(rings - 2, s + 1), idx(rings - 2, s)))
    for r in range(rings - 2):
        for s in range(sectors):
            a, b, c, d = idx(r, s), idx(r + 1, s), idx(r + 1, s + 1), idx(r, s + 1)
            faces.append((a, b, c))
            faces.append((a, c, d))
    return v, np.asarray(faces, np.int64)


def box(size=(1.0, 1.0, 1.0)):
    """An axis-aligned box of the given edge lengths centred at the origin, 12 triangles."""
    half = np.broadcast_to(np.asarray(size, np.float64), (3,)) * 0.5
    corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], np.float64) * half
    # Corner index = 4 * (x > 0) + 2 * (y > 0) + (z > 0); each side's quad counter-clockwise from outside.
    quads = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    faces = [(a, b, c) for a, b, c, d in quads] + [(a, c, d) for a, b, c, d in quads]
    return corners, np.asarray(faces, np.int64)


def plane(size=(10.0, 10.0)):
    """A rectangle in y = 0 facing +y, two triangles split along one diagonal."""
    sx, sz = np.broadcast_to(np.asarray(size, np.float64), (2,)) * 0.5
    v = np.array([[-sx, 0, -sz], [-sx, 0, sz], [sx, 0, sz], [sx, 0, -sz]], np.float64)
    return v, np.array([[0, 1, 2], [0, 2, 3]], np.int64)


def cylinder(radius: float = 0.5, height: float = 1.0, sections: int = 64):
    """A capped cylinder along y, centred at the origin; caps are fans around their centres."""
    phi = np.arange(sections) * (2.0 * np.pi / sections)
    ring = np.stack([np.cos(phi), np.zeros_like(phi), -np.sin(phi)], 1) * radius
    h = height / 2.0
    v = np.vstack([ring + [0, -h, 0], ring + [0, h, 0], [[0, -h, 0], [0, h, 0]]])
    i = np.arange(sections)
    j = (i + 1) % sections
    bottom, top = 2 * sections, 2 * sections + 1
    faces = np.concatenate([
        np.stack([i, j, j + sections], 1), np.stack([i, j + sections, i + sections], 1),  # side
        np.stack([np.full(sections, bottom), j, i], 1),  # bottom cap, facing -y
        np.stack([np.full(sections, top), i + sections, j + sections], 1),  # top cap, facing +y
    ])
    return v, faces.astype(np.int64)


def torus_knot(p: int = 2, q: int = 3, radius: float = 1.0, tube: float = 0.15, segments=(1024, 64)):
    """A (p, q) torus knot: the curve ((2 + cos q t) cos p t, -sin q t, (2 + cos q t) sin p t) radius/3,
    swept by a circle of radius tube in its Frenet frame; 2 * segments[0] * segments[1] triangles,
    so a procedural mesh of any size (segments = [2048, 128]: 524,288 triangles)."""
    n, m = int(segments[0]), int(segments[1])
    t = np.arange(n) * (2.0 * np.pi / n)

    def curve(t):
        r = 2.0 + np.cos(q * t)
        return np.stack([r * np.cos(p * t), -np.sin(q * t), r * np.sin(p * t)], -1) * (radius / 3.0)

    h = 1e-4  # central differences: the frame's error (h^2) is far below the mesh's own
    c, d1 = curve(t), (curve(t + h) - curve(t - h)) / (2 * h)
    d2 = (curve(t + h) - 2 * curve(t) + curve(t - h)) / (h * h)
    tangent = d1 / np.linalg.norm(d1, axis=1, keepdims=True)
    binormal = np.cross(d1, d2)  # a torus knot's curvature never vanishes, so the frame is defined
    binormal /= np.linalg.norm(binormal, axis=1, keepdims=True)
    normal = np.cross(binormal, tangent)
    phi = np.arange(m) * (2.0 * np.pi / m)
    v = c[:, None] + tube * (np.cos(phi)[None, :, None] * normal[:, None] + np.sin(phi)[None, :, None] * binormal[:, None])
    i, j = np.meshgrid(np.arange(n), np.arange(m), indexing="ij")
    a, b = i * m + j, ((i + 1) % n) * m + j
    c2, d = ((i + 1) % n) * m + (j + 1) % m, i * m + (j + 1) % m
    faces = np.concatenate([np.stack([a, c2, b], -1).reshape(-1, 3), np.stack([a, d, c2], -1).reshape(-1, 3)])  # outward
    return v.reshape(-1, 3), faces.astype(np.int64)


def triangles(vertices, faces, uv=None, colors=None):
    """Explicit vertices and faces, as given (uv and colours per vertex are read by the scene reader)."""
    return np.asarray(vertices, np.float64).reshape(-1, 3), np.asarray(faces, np.int64).reshape(-1, 3)


# --- the same triangles with texture coordinates (v = 0 at an image's bottom row) ---------------------


def plane_uv(size=(10.0, 10.0)):
    """The plane with the whole texture on it, upright seen from +z: u along +x, v along -z."""
    v, f = plane(size)
    sx, sz = np.broadcast_to(np.asarray(size, np.float64), (2,)) * 0.5
    return v, f, np.stack([(v[:, 0] + sx) / (2 * sx), (sz - v[:, 2]) / (2 * sz)], 1)


def box_uv(size=(1.0, 1.0, 1.0)):
    """The box with the whole texture on each side, upright seen from outside (the top side's up is
    -z, the bottom's +z): its 8 corners split into 4 per side, the same 12 triangles."""
    corners, faces = box(size)
    half = np.broadcast_to(np.asarray(size, np.float64), (3,)) * 0.5
    vertices, uv = corners[faces].reshape(-1, 3), np.zeros((3 * len(faces), 2))
    p = vertices.reshape(-1, 3, 3)
    n = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    up = np.where(np.abs(n[:, 1:2]) > 0.5, np.array([[0.0, 0.0, -1.0]]) * np.sign(n[:, 1:2]), [[0.0, 1.0, 0.0]])
    right = np.cross(up, n)
    for k in range(3):  # positions relative to the centre, over the side's extent along each axis
        uv[k::3, 0] = 0.5 + np.einsum("ij,ij->i", p[:, k], right) / (2 * np.abs(right) @ half)
        uv[k::3, 1] = 0.5 + np.einsum("ij,ij->i", p[:, k], up) / (2 * np.abs(up) @ half)
    return _welded(vertices, np.arange(len(vertices), dtype=np.int64).reshape(-1, 3), uv)


def uv_sphere_uv(radius: float = 1.0, segments=(32, 64)):
    """The latitude-longitude sphere with u = longitude / 360 degrees (from +x towards -z) and v = 1 at
    the north pole: its seam and pole vertices split where their uv differ, the same triangles."""
    v, f = uv_sphere(radius, segments)
    rings, sectors = int(segments[0]), int(segments[1])
    # Each corner's latitude index (0: north pole .. rings: south pole) and longitude index, counted
    # past the seam (sectors, not 0) and mid-sector at a pole, in uv_sphere's face order.
    s = np.arange(sectors, dtype=np.float64)
    caps_ring = np.tile([[0, 1, 1], [rings, rings - 1, rings - 1]], (sectors, 1))
    caps_col = np.stack([np.stack([s + 0.5, s, s + 1], 1), np.stack([s + 0.5, s + 1, s], 1)], 1).reshape(-1, 3)
    r, s2 = (a.ravel().astype(np.float64) for a in np.meshgrid(np.arange(rings - 2), s, indexing="ij"))
    body_ring = np.stack([np.stack([r + 1, r + 2, r + 2], 1), np.stack([r + 1, r + 2, r + 1], 1)], 1).reshape(-1, 3)
    body_col = np.stack([np.stack([s2, s2, s2 + 1], 1), np.stack([s2, s2 + 1, s2 + 1], 1)], 1).reshape(-1, 3)
    ring, col = np.concatenate([caps_ring, body_ring]), np.concatenate([caps_col, body_col])
    return _welded(v[f.reshape(-1)], np.arange(f.size, dtype=np.int64).reshape(-1, 3),
                   np.stack([col / sectors, 1.0 - ring / rings], -1).reshape(-1, 2))


def _welded(vertices, faces, uv):
    """One vertex per distinct (position, uv)."""
    keys = np.ascontiguousarray(np.concatenate([vertices, uv], 1) + 0.0)
    _, first, inverse = np.unique(keys.view(np.dtype((np.void, 40))).ravel(), return_index=True, return_inverse=True)
    return vertices[first], inverse.reshape(-1)[faces].astype(np.int64), uv[first]


# name -> (builder, {parameter: (kind, default)}); kinds are checked by the scene reader.
SHAPES = {
    "sphere": (sphere, {"radius": ("positive", 1.0), "subdivisions": ("int0", 3)}),
    "uv_sphere": (uv_sphere, {"radius": ("positive", 1.0), "segments": ("int2", [32, 64])}),
    "box": (box, {"size": ("size3", [1.0, 1.0, 1.0])}),
    "plane": (plane, {"size": ("size2", [10.0, 10.0])}),
    "cylinder": (cylinder, {"radius": ("positive", 0.5), "height": ("positive", 1.0), "sections": ("int3", 64)}),
    "torus_knot": (torus_knot, {"p": ("int1", 2), "q": ("int1", 3), "radius": ("positive", 1.0), "tube": ("positive", 0.15),
                                "segments": ("int2", [1024, 64])}),
    "triangles": (triangles, {"vertices": ("points", None), "faces": ("faces", None), "uv": ("uv", None),
                              "colors": ("colors", None)}),
}

# The shapes whose texture coordinates are defined, and their builders with uv.
WITH_UV = {"plane": plane_uv, "box": box_uv, "uv_sphere": uv_sphere_uv}

# The keys of an [[objects]] table besides its shape's parameters.
OBJECT_KEYS = {"name", "mesh", "shape", "material", "scale", "rotate", "translate", "smooth", "up"}


def read_shape(r: TableReader, textured: bool):
    """The table's shape (``shape = "..."``) built from its parameters: (kind, vertices, faces, uv, colors),
    uv where ``textured`` and the shape has them (WITH_UV) or given (triangles), colours where given."""
    kind = r.string("shape")
    if kind not in SHAPES:
        r.fail("shape", f"unknown shape '{kind}'{did_you_mean(kind, SHAPES)}; expected one of: {', '.join(SHAPES)}")
    builder, params = SHAPES[kind]
    r.check_keys(OBJECT_KEYS | set(params))
    args = {p: _read_parameter(r, p, ptype, default) for p, (ptype, default) in params.items()
            if p in r.table or ptype not in ("uv", "colors")}
    if kind == "triangles":
        n = len(args["vertices"])
        for key in ("uv", "colors"):
            if key in args and len(args[key]) != n:
                r.fail(key, f"expected one per vertex ({n}), got {len(args[key])}")
        uv, colors = args.pop("uv", None), args.pop("colors", None)
        return (kind, *builder(**args), uv, colors)
    if textured and kind in WITH_UV:
        return (kind, *WITH_UV[kind](**args), None)
    return (kind, *builder(**args), None, None)


def _read_parameter(r: TableReader, p: str, ptype: str, default):
    """One shape parameter of SHAPES, checked as its kind says."""
    if ptype == "positive":
        return r.number(p, default, lo=0.0, lo_open=True)
    if ptype.startswith("int"):
        if isinstance(default, list):
            v = r.vector(p, default, n=2)
            if any(x != int(x) or x < 3 for x in v):
                r.fail(p, f"expected 2 integers >= 3, got {list(v)}")
            return tuple(int(x) for x in v)
        return r.integer(p, default, lo=int(ptype[3:]), hi=8 if p == "subdivisions" else 100000)
    if ptype in ("size3", "size2"):
        v = r.vector(p, default, n=int(ptype[-1]), allow_scalar=True)
        if min(v) <= 0:
            r.fail(p, f"expected positive sizes, got {list(v)}")
        return v
    if ptype in ("points", "uv", "colors"):
        width, what, min_rows = {"points": (3, "[x, y, z] points (at least 3)", 3), "uv": (2, "[u, v] per vertex", 1),
                                 "colors": (3, "[r, g, b] per vertex", 1)}[ptype]
        return r.rows(p, width, what, min_rows, nonneg=ptype == "colors")
    v = r.table.get(p)  # "faces"
    try:
        a = np.asarray(v)
    except (TypeError, ValueError):
        a = None
    if a is None or a.ndim != 2 or a.shape[1] != 3 or len(a) < 1 or a.dtype.kind not in "iu":
        r.fail(p, f"expected a list of [i, j, k] integer vertex indices, got {show(v)}")
    return a.astype(np.int64)
