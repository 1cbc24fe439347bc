"""What a render holds in memory: the bytes of the geometry arrays the kernels read and of Warp's
BVH, the frame's buffers, and the process's peak resident set size, for the stats and `warprt info`."""

from __future__ import annotations

import resource
import sys


def bvh_bytes(n_triangles: int) -> int:
    """Host bytes wp.Mesh allocates for its BVH over n triangles, from Warp's layout (native
    mesh.cpp and bvh.cpp, Warp 1.19): two vec3 bounds per triangle, 2n - 1 nodes of two 16-byte
    halves and a parent index, and the primitive order. Allocated, not all of it resident: with
    several triangles per leaf the tree uses fewer nodes than it reserves."""
    n = int(n_triangles)
    if n <= 0:
        return 0
    return 2 * 12 * n + (2 * n - 1) * (16 + 16 + 4) + 4 * n + 4


def geometry_memory(geom) -> dict:
    """Bytes by role for a Geometry: the arrays as allocated (Warp's own count) and the BVH."""
    d = geom.data

    def size(*arrays):
        return int(sum(a.capacity for a in arrays if a is not None))

    out = {
        "vertices": size(geom.points),  # float32 vec3; with the BVH's box corners after the vertices
        "indices": size(geom.indices),  # int32, 3 per triangle
        "normals": size(d.normals),
        "per_triangle": size(d.tri_material, d.tri_smooth),
        "materials_lights": size(d.ka, d.kd, d.ks, d.kr, d.shininess, d.light_pos, d.light_color),
        "bvh": bvh_bytes(geom.triangle_count) if getattr(geom, "mesh", None) is not None else 0,
    }
    out["total"] = sum(out.values())
    return out


def frame_memory(geom, image_bytes: int, raster_bytes: int, shadow_grid_bytes: int = 0, mirrors_bytes: int = 0) -> dict:
    """The stats' memory record of one frame: geometry by role, the image and ray-count buffers, the
    Z-buffer's per-sample buffers (0 when no first hit came from it), the shadow rays' light-space grid
    (0 when they were traced; kept with the geometry), the planar mirrors' unfolded scenes and stored
    rasters (0 when reflection rays were traced), and the peak RSS so far."""
    return {"geometry": geometry_memory(geom), "image": int(image_bytes), "raster": int(raster_bytes),
            "shadow_grid": int(shadow_grid_bytes), "mirrors": int(mirrors_bytes), "peak_rss": peak_rss()}


def peak_rss() -> int:
    """The process's peak resident set size in bytes (ru_maxrss is KiB on Linux, bytes on macOS)."""
    r = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return int(r if sys.platform == "darwin" else r * 1024)


def human(n: float) -> str:
    for unit in ("B", "KiB", "MiB", "GiB"):
        if abs(n) < 1024 or unit == "GiB":
            return f"{n:.0f} {unit}" if unit == "B" else f"{n:.1f} {unit}"
        n /= 1024.0
    return f"{n:.1f} GiB"
