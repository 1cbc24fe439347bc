"""What a render holds in memory: the bytes of the geometry arrays the kernels read and of Warp's
BVH, the frame's buffers, the process's peak resident set size, and the one estimate of what a frame
will need, checked against what the machine has before anything is allocated (and shown in the stats)."""

from __future__ import annotations

import resource
import sys
from pathlib import Path

from ..errors import SceneError

# What a frame adds to the peak resident set size, measured (2 cores, Warp 1.19, NumPy 2.4): peak_rss
# of `warprt render ok.toml --width S --height S -q --stats` (a sphere, tests/cli/corpus/ok.toml) at
# S = 256, 2048 and 4096, the slope between 2048 and 4096:
# - traced first hits: 39.0 bytes per pixel for .png, .npy and .exr alike (the float32 image and
#   int32 ray counts Warp fills, 24 bytes; the image's host copy, 12; the rest the writer's);
# - first hits from the Z-buffer (--primary zbuffer): 28.1 bytes more per sample (spp 1 and 4);
# - the Z-buffer renderer (--algorithm zbuffer): 33.0 bytes per pixel at spp 1, 93.1 at spp 4.
# Geometry: spheres of 327,680 and 1,310,720 triangles at 8x6 pixels, the peak's growth less the
# scene's own float64 arrays (read before the check): 252 bytes per triangle, about half a vertex each.
TRACE_BYTES_PER_PIXEL = 40
RASTER_BYTES_PER_SAMPLE = 28  # 1/z and its nearest rival (float64 each), the face (int32), (u, v): 8 + 8 + 4 + 8
ZBUFFER_BYTES_PER_PIXEL = 24  # the image and its host copy; the measured 13 stays below it
ZBUFFER_BYTES_PER_SAMPLE = 20  # no rival depth in a plain Z-buffer image
GEOMETRY_BYTES_PER_TRIANGLE = 200
GEOMETRY_BYTES_PER_VERTEX = 100


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

    def size(*arrays):  # an array two roles share (the uvs: shading's and the uv AOV's) counted once
        return int(sum(a.capacity for a in {id(a): a for a in arrays if a is not None}.values()))

    out = {
        "vertices": size(geom.points),  # float32 vec3; with the BVH's box corners after the vertices
        "indices": size(geom.indices),  # int32, 3 per triangle
        "normals": size(d.normals),
        "per_triangle": size(d.tri_material, d.tri_smooth, *(getattr(geom, "object_ids", None) or ())),
        "uv_colors": size(d.uvs, d.colors, *(getattr(geom, "object_uv", None) or ())),
        "materials_lights": size(d.ka, d.kd, d.ks, d.kr, d.shininess, d.ka_map, d.kd_map, d.ks_map, d.ior,
                                 d.transmittance, d.absorption, d.light_pos, d.light_color),
        "textures": int(getattr(geom, "texture_bytes", 0)),
        "bvh": bvh_bytes(geom.triangle_count) if getattr(geom, "mesh", None) is not None else 0,
    }
    out["total"] = sum(out.values())
    return out


def frame_memory(geom, image_bytes: int, raster_bytes: int, aov_bytes: int = 0, shadow_grid_bytes: int = 0,
                 mirrors_bytes: int = 0) -> dict:
    """The stats' memory record of one frame: geometry by role, the image and ray-count buffers, the
    Z-buffer's per-sample buffers (0 when no first hit came from it), the AOVs' per-pixel buffers (0
    when none were asked for), the shadow rays' light-space grid (0 when they were traced; kept with
    the geometry), the planar mirrors' unfolded scenes and stored rasters (0 when reflection rays were
    traced), and the peak RSS so far."""
    return {"geometry": geometry_memory(geom), "image": int(image_bytes), "raster": int(raster_bytes),
            "aovs": int(aov_bytes), "shadow_grid": int(shadow_grid_bytes), "mirrors": int(mirrors_bytes),
            "peak_rss": peak_rss()}


def frame_estimate(scene, samples: int, raster: bool, algorithm: str = "raytrace") -> dict:
    """Bytes a frame of ``scene`` will add to the process, by role (the calibration above): the image
    buffers, the Z-buffer's per-sample buffers (``raster``: first hits from it; ``samples`` per pixel),
    and the geometry with its BVH. The same numbers are checked before a render and shown in the stats."""
    cam = scene.camera
    pixels = cam.width * cam.height
    triangles = scene.triangle_count
    vertices = int(sum(len(o.vertices) for o in scene.objects))
    if algorithm == "zbuffer":
        image, raster_bytes = ZBUFFER_BYTES_PER_PIXEL * pixels, ZBUFFER_BYTES_PER_SAMPLE * pixels * samples
    else:
        image, raster_bytes = TRACE_BYTES_PER_PIXEL * pixels, RASTER_BYTES_PER_SAMPLE * pixels * samples if raster else 0
    geometry = GEOMETRY_BYTES_PER_TRIANGLE * triangles + GEOMETRY_BYTES_PER_VERTEX * vertices
    out = {"image": int(image), "raster": int(raster_bytes), "geometry": int(geometry)}
    out["total"] = sum(out.values())
    return out


def available_memory(device: str = "cpu") -> tuple[int | None, str]:
    """The bytes this process can still take, and what sets that: on a GPU the device's free memory (the
    frame's buffers live there); on the CPU the least of the memory the kernel could give without swapping
    (MemAvailable), the room left under the cgroup's limit (a container's memory.max, or
    memory.limit_in_bytes under cgroup v1) and under RLIMIT_AS. None where none is known."""
    if device != "cpu":
        from .._warp import wp

        d = wp.get_device(device)
        return (int(d.free_memory), f"free on {d.alias} ({d.name})") if d.is_cuda else (None, "")
    found = []
    meminfo = _read("/proc/meminfo")
    for line in meminfo.splitlines():
        if line.startswith("MemAvailable:"):
            found.append((int(line.split()[1]) * 1024, "available memory (MemAvailable)"))
    for limit_file, usage_file, where in _cgroup_files():
        limit, usage = _read(limit_file).strip(), _read(usage_file).strip()
        if limit.isdigit() and usage.isdigit() and int(limit) < 2**60:
            found.append((max(0, int(limit) - int(usage)), f"left under the memory limit of {human(int(limit))} ({where})"))
    soft, _ = resource.getrlimit(resource.RLIMIT_AS)
    if soft != resource.RLIM_INFINITY:
        size = next((int(l.split()[1]) * 1024 for l in _read("/proc/self/status").splitlines() if l.startswith("VmSize:")), 0)
        found.append((max(0, soft - size), f"left of the address space limit of {human(soft)} (RLIMIT_AS)"))
    return min(found) if found else (None, "")


def _cgroup_files():
    """(limit, usage, name) of this process's memory cgroup and those above it, v2 and v1."""
    for line in _read("/proc/self/cgroup").splitlines():
        parts = line.split(":", 2)
        if len(parts) != 3:
            continue
        _, controllers, path = parts
        if controllers == "":
            root, names = Path("/sys/fs/cgroup"), ("memory.max", "memory.current")
        elif "memory" in controllers.split(","):
            root, names = Path("/sys/fs/cgroup/memory"), ("memory.limit_in_bytes", "memory.usage_in_bytes")
        else:
            continue
        # Inside a container the cgroup's own folder is usually mounted as the root.
        folders = {root}
        p = root / path.lstrip("/")
        while p != root and root in p.parents:
            folders.add(p)
            p = p.parent
        for folder in sorted(folders):
            yield folder / names[0], folder / names[1], f"cgroup {folder.name if folder != root else '/'}"


def _read(path) -> str:
    try:
        return Path(path).read_text()
    except OSError:
        return ""


def check_frame_memory(scene, estimate: dict, device: str = "cpu"):
    """Refuse a frame that needs more memory than the machine (or the GPU ``device``) has, before allocating
    any of it: one line with both numbers, rather than an allocation failure deep in Warp or the OOM killer."""
    available, what = available_memory(device)
    if available is None or estimate["total"] <= available:
        return
    cam = scene.camera
    names = {"image": "image buffers", "raster": "Z-buffer", "geometry": "geometry and BVH"}
    parts = ", ".join(f"{names[k]} {human(v)}" for k, v in estimate.items() if k in names and v)
    raise SceneError(scene.source, "camera.width, camera.height",
                     f"a {cam.width}x{cam.height} frame needs about {human(estimate['total'])} of memory ({parts}), "
                     f"more than the {human(available)} {what}")


def peak_rss() -> int:
    """The process's peak resident set size in bytes. On Linux VmHWM, this program's own: ru_maxrss
    survives exec, so a warprt started from a large process (a test runner, a notebook) would report
    that process's size at the fork (measured: 356 MB for a 512x512 frame run from pytest, against 198).
    Elsewhere ru_maxrss (KiB on Linux, bytes on macOS)."""
    for line in _read("/proc/self/status").splitlines():
        if line.startswith("VmHWM:"):
            return int(line.split()[1]) * 1024
    r = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return int(r if sys.platform == "darwin" else r * 1024)


def human(n: float) -> str:
    for unit in ("B", "KiB", "MiB", "GiB"):
        if abs(n) < 1024 or unit == "GiB":
            return f"{n:.0f} {unit}" if unit == "B" else f"{n:.1f} {unit}"
        n /= 1024.0
    return f"{n:.1f} GiB"
