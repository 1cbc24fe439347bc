"""The Z-buffer's host side: the per-sample buffers of one rasterization (ZBuffer, handing on
kernels.raster.Fragments) and the eye-on-a-surface test that sends a view to the tracer."""

from __future__ import annotations

import math

import numpy as np

from .._warp import wp
from ..geometry import Geometry
from ..options import RASTER_TILE
from ..kernels import (CLIP_SCALE, MARGIN_PX, Fragments, count_kernel, fill_kernel, project_kernel,
                       raster_camera, raster_kernel, raster_pixel_kernel, uncertain_np)
from ..scene import EffectSet, camera_basis
from .caches import EYE_TESTS_KEPT
from .launch import launch_bands
from .samples import sample_grid
from .stats import timed


def clip_distance(geometry: Geometry, eye=(0.0, 0.0, 0.0)) -> float:
    """z_clip = CLIP_SCALE R, R = sqrt(3) (max |coordinate| + max |eye|) bounding every vertex's
    distance from the eye (``eye`` relative to the frame origin, as Geometry.eye_offset gives it)."""
    reach = (geometry.reach + float(np.abs(np.asarray(eye, np.float64)).max())) * math.sqrt(3.0)
    return CLIP_SCALE * max(reach, 1e-30)


def eye_on_surface(geometry: Geometry, basis, memo: dict | None = None) -> bool:
    """Whether some triangle comes within reach of the eye that the rasterizer clips: its plane that
    close, and the eye inside its box grown by as much. The clip plane z = z_clip cuts away points
    that camera rays (at most the corner ray's angle theta off the axis) reach within
    z_clip / cos(theta); twice that is the reach. The tracer's rays, which start at the eye and keep
    hits from t = 0, hit such a triangle there, as they do one the eye lies on. Hybrid rendering
    traces the first hits of such a view: a camera placed on (or a hair from) a surface."""
    eye = geometry.eye_offset(basis.eye)
    cos_corner = basis.d_f / math.sqrt(basis.d_f ** 2 + (basis.h / 2.0) ** 2 + (basis.w / 2.0) ** 2)
    tol = 2.0 * clip_distance(geometry, eye) / cos_corner
    cache = {} if memo is None else memo  # a Renderer's FrameCaches.eye_on_surface, across its frames
    key = (tol, tuple(eye.tolist()))
    if key not in cache:
        if len(cache) >= EYE_TESTS_KEPT:
            cache.clear()
        cache[key] = _eye_on_surface(geometry, tol, eye.astype(np.float64))
    return cache[key]


def _eye_on_surface(geometry: Geometry, tol: float, eye: np.ndarray) -> bool:
    if geometry.triangle_count == 0:
        return False
    lower, upper = geometry.triangle_boxes()
    in_box = np.all((lower - eye <= tol) & (upper - eye >= -tol), axis=1)
    if not in_box.any():
        return False
    t = geometry.points_np.astype(np.float64)[geometry.indices_np.reshape(-1, 3)[in_box]] - eye
    n = np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])
    length = np.linalg.norm(n, axis=1)
    plane = np.abs(np.einsum("ij,ij->i", n, t[:, 0]))  # |n . p0|: |n| times the eye's distance to the plane
    return bool(np.any(plane <= tol * length))


def empty_fragments(device) -> Fragments:
    """Fragments of no samples: what the trace kernel gets when no first hit comes from the Z-buffer."""
    frags = Fragments()
    frags.face = wp.empty(0, dtype=wp.int32, device=device)
    frags.inv_depth = wp.empty(0, dtype=wp.float64, device=device)
    frags.uv = wp.empty(0, dtype=wp.vec2, device=device)
    frags.rival_inv_depth = wp.empty(0, dtype=wp.float64, device=device)
    return frags


def culled_faces(scene, geometry: Geometry, eye) -> np.ndarray:
    """Per triangle, whether the camera at ``eye`` (relative to the frame origin) sees it from behind
    and its material is single-sided: what the tracer's rays pass through (trace.culled), so a plain
    Z-buffer image does not draw it. The eye's side of the triangle's plane, in float64."""
    single = np.array([not m.double_sided for m in geometry.slot_materials(scene)] or [False])
    faces = geometry.indices_np.reshape(-1, 3)[: geometry.triangle_count]
    p = geometry.points_np.astype(np.float64)[faces]
    n = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    behind = np.einsum("ij,ij->i", p[:, 0] - np.asarray(eye, np.float64), n) > 0.0
    return single[geometry.tri_material_np[: geometry.triangle_count]] & behind


class ZBuffer:
    """Owns the per-sample buffers of one scene's rasterization (self.fragments)."""

    def __init__(self, scene, geometry: Geometry, fx: EffectSet, device: str = "cpu", tile: int = RASTER_TILE,
                 track_uncertain: bool = True, margin: float = MARGIN_PX, fragments: Fragments | None = None,
                 per_pixel: bool | None = None):
        """``fragments``: buffers of this size to draw into instead of new ones, every sample cleared
        (the virtual cameras pass one from chain to chain, cleared as they gather it). ``per_pixel``: depth-
        test with a thread per pixel (raster_pixel_kernel, the same Fragments) rather than per tile; None:
        on a GPU (its many threads), not on the CPU (where a tile's thread clips each triangle once)."""
        cam = scene.camera
        self.geometry, self.device, self.tile = geometry, device, int(tile)
        self.per_pixel = wp.get_device(device).is_cuda if per_pixel is None else bool(per_pixel)
        self.track_uncertain = track_uncertain
        self.basis = camera_basis(cam)
        self.eye = geometry.eye_offset(cam.eye)  # the tracer's camera ray origin
        self.k, side = sample_grid(scene, fx)
        self.samples = side * side
        # track_uncertain: fill rival_inv_depth for hybrid rendering; a plain Z-buffer image skips it.
        self.camera = raster_camera(self.basis, clip_distance(geometry, self.eye), margin if track_uncertain else 0.0,
                                    self.eye)
        n = cam.width * cam.height * self.samples
        if fragments is not None:
            self.fragments, self.times, self.pairs = fragments, {}, 0
            return
        frags = Fragments()
        frags.face = wp.full(n, -1, dtype=wp.int32, device=device)
        frags.inv_depth = wp.zeros(n, dtype=wp.float64, device=device)  # 0 is "nothing yet"
        frags.uv = wp.zeros(n, dtype=wp.vec2, device=device)
        frags.rival_inv_depth = wp.zeros(n if track_uncertain else 0, dtype=wp.float64, device=device)  # 0: none
        self.fragments = frags
        self.times: dict = {}
        self.pairs = 0

    @property
    def nbytes(self) -> int:
        f = self.fragments
        return int(f.face.capacity + f.inv_depth.capacity + f.uv.capacity + f.rival_inv_depth.capacity)

    def rasterize(self, threads: int, bands: int, tiles: np.ndarray | None = None, skip: np.ndarray | None = None,
                  pool=None):
        """Project, bin and depth-test every triangle; times["project"|"bin"|"raster"] in seconds. With
        ``tiles`` (one flag per raster tile, row-major from the bottom), only those tiles' samples; with
        ``skip`` (one flag per triangle: culled_faces), not those triangles."""
        g, c, dev = self.geometry, self.camera, self.device
        data = g.data
        k = self.k if self.samples > 1 else 1
        with timed(self.times, "project"):
            bounds = wp.empty(max(g.triangle_count, 1), dtype=wp.vec4i, device=dev)
            if g.triangle_count:
                # A few thousand triangles per launch: below that, launching costs more than projecting.
                launch_bands(project_kernel, lambda first: [data, c, k, first, bounds], g.triangle_count, threads,
                             max(1, min(bands, g.triangle_count // 4096)), dev, pool=pool)
            if skip is not None and skip.any():
                b = bounds.numpy()
                b[: g.triangle_count][skip] = (1, 0, 1, 0)  # an empty rectangle: in no tile
                bounds = wp.array(b, dtype=wp.vec4i, device=dev)

        # Binning: count per tile, scan, fill. One launch each: Warp's atomics are plain
        # read-modify-writes on the CPU, safe within a launch (one thread) but not across launches.
        with timed(self.times, "bin"):
            tile = self.tile
            tiles_x, tiles_y = -(-c.width // tile), -(-c.height // tile)
            n_tiles = tiles_x * tiles_y
            tile_count = wp.zeros(n_tiles, dtype=wp.int32, device=dev)
            mask = (wp.array(np.asarray(tiles, np.int32), dtype=wp.int32, device=dev) if tiles is not None
                    else wp.empty(0, dtype=wp.int32, device=dev))
            wp.launch(count_kernel, dim=g.triangle_count, inputs=[bounds, tile, tiles_x, mask, tile_count], device=dev)
            # The scan on the device; the list's length (4 bytes) is all the host reads, to allocate it.
            starts = wp.zeros(n_tiles + 1, dtype=wp.int32, device=dev)
            wp.utils.array_scan(tile_count, starts[1:], inclusive=True)
            self.pairs = int(starts[n_tiles:].numpy()[0])
            cursor = wp.clone(starts[:n_tiles])
            faces = wp.empty(max(self.pairs, 1), dtype=wp.int32, device=dev)
            wp.launch(fill_kernel, dim=g.triangle_count, inputs=[bounds, tile, tiles_x, mask, cursor, faces], device=dev)
            wp.synchronize_device(dev)

        with timed(self.times, "raster"):
            samples, frags = self.samples, self.fragments
            kernel, count = (raster_pixel_kernel, c.width * c.height) if self.per_pixel else (raster_kernel, n_tiles)
            launch_bands(kernel, lambda first: [data, c, starts, faces, tiles_x, tile, k, samples, first, frags],
                         count, threads, max(bands, 4 * threads), dev, pool=pool)

    def uncertain(self) -> np.ndarray:
        """Where the rasterizer's visible triangle may not be the tracer's, (height, width, samples):
        hybrid.uncertain() of every sample."""
        if not self.track_uncertain:
            raise ValueError("this ZBuffer was made with track_uncertain=False: it has no uncertain samples to report")
        f = self.fragments
        shape = (self.basis.height, self.basis.width, self.samples)
        return uncertain_np(f.inv_depth.numpy(), f.rival_inv_depth.numpy()).reshape(shape)

    def faces(self) -> np.ndarray:
        """The visible triangle of every sample, (height, width, samples), -1 where none."""
        return self.fragments.face.numpy().reshape(self.basis.height, self.basis.width, self.samples)
