"""A frame's virtual cameras for planar mirrors (the host side of kernels/mirror.py): the chains of planar
groups its reflection rays follow, each chain's unfolded scene rasterized from the camera over the tiles
its rays cover, and the Mirrors record of those rasters that the trace kernel reads; kept in a
Renderer's FrameCaches for the next frames of the same view (view_key)."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from .._warp import wp
from ..geometry import MAX_GROUPS, mirrored_geometry, planar_groups
from ..geometry.planar import reflect_points
from ..kernels import MAX_BOUNCES, MIRROR_MARGIN_PX, Mirrors, camera_data, gather_kernel, probe_kernel, raster_camera
from ..scene import camera_basis
from .caches import FrameCaches
from .launch import launch_bands
from .zbuffer import RASTER_TILE, ZBuffer

MAX_CHAINS = 12
PROBES_PER_SIDE = 2  # traced camera rays per raster tile side, to find the chains a frame's rays follow
# The stored rasters: face (int32), 1/z and its rival (float64 each) per sample of a stored tile.
BYTES_PER_SAMPLE = 4 + 8 + 8
MAX_BYTES = 256 * 2**20
KEEP_VIEWS = 2  # views whose virtual cameras a Renderer keeps (a stereo pair), within MAX_BYTES in all


def empty_mirrors(device) -> Mirrors:
    """Mirrors of no chain: what the trace kernel gets when reflection rays are traced."""
    m = Mirrors()
    ints = lambda n=1: wp.zeros(n, dtype=wp.int32, device=device)
    m.group, m.first_chain, m.next_chain, m.level, m.tile_slot, m.face, m.decided = (ints() for _ in range(7))
    m.plane = wp.zeros(MAX_BOUNCES, dtype=wp.vec4d, device=device)
    m.side, m.inv_depth, m.rival_inv_depth = (wp.zeros(1, dtype=wp.float64, device=device) for _ in range(3))
    m.groups = m.tiles = m.tiles_x = m.tile = m.samples = m.k = 1
    m.pixel_angle = wp.float64(0.0)
    return m


def view_key(scene, geom, fx) -> tuple:
    """Everything a frame's virtual cameras depend on besides the Geometry's triangles: the camera, the
    samples, the bounces and which material slots reflect (k_r > 0 in float32, as the kernels read it).
    Lights, colours and how much a mirror reflects are not in it: a frame that changes only those reuses
    the rasters."""
    spp = scene.render.spp if fx.supersampling else 1
    kr = np.asarray([m.reflectivity for m in geom.slot_materials(scene)] or [[0, 0, 0]], np.float32)
    reflective = tuple(bool(r) for r in kr.reshape(-1, 3).max(axis=1) > 0.0)
    # The whole (frozen) Camera, so that a field it gains is part of the key too.
    return (scene.camera, int(spp), min(MAX_BOUNCES, scene.render.max_depth - 1), reflective)


def kept_mirror_frame(caches: FrameCaches, key: tuple) -> "MirrorFrame | None":
    """The virtual cameras ``caches`` keep for the view ``key`` (view_key), or None."""
    return caches.virtual_cameras.get(key)


def mirror_frame(scene, geom, data, fx, key: tuple, threads: int, bands: int, device: str,
                 caches: FrameCaches, pool=None) -> tuple["MirrorFrame", bool]:
    """The virtual cameras of the view ``key`` (view_key) and whether ``caches`` (the Renderer's, for
    ``geom``) kept them from an earlier frame: a static camera's rasters are the same arrays frame after
    frame, so the image is the one a fresh build gives, to the bit; only the count of rays decided
    starts again from zero. ``pool``: the threads the bands run on (launch_bands)."""
    kept = caches.virtual_cameras
    frame = kept.get(key)
    if frame is not None:
        if frame.mirrors is not None:
            frame.mirrors.decided.zero_()
        return frame, True
    frame = MirrorFrame(scene, geom, data, fx, threads, bands, device, caches=caches, pool=pool)
    kept[key] = frame
    # The oldest views go first, down to KEEP_VIEWS and MAX_BYTES (this frame's always stays).
    while len(kept) > 1 and (len(kept) > KEEP_VIEWS or sum(f.nbytes for f in kept.values()) > MAX_BYTES):
        kept.pop(next(iter(kept)))
    return frame, False


def tiles_seen(tri: np.ndarray, basis, eye: np.ndarray, tile: int) -> np.ndarray:
    """The raster tiles (row-major from the bottom, as the rasterizer numbers them) that triangles (T, 3, 3)
    may cover, from their projected boxes; every tile for a triangle reaching behind the eye. Only how
    much is rasterized depends on it: a ray in a tile left out is traced."""
    tiles_x, tiles_y = -(-basis.width // tile), -(-basis.height // tile)
    seen = np.zeros((tiles_y, tiles_x), bool)
    if not len(tri):
        return seen.reshape(-1)
    rel = tri - eye
    z = -(rel @ basis.z_e)
    if np.any(z <= 1e-9 * np.abs(rel).max()):
        return np.ones(tiles_x * tiles_y, bool)
    f_x, f_y = basis.d_f * basis.width / basis.w, basis.d_f * basis.height / basis.h
    X = basis.width / 2.0 + f_x * (rel @ basis.x_e) / z
    Y = basis.height / 2.0 + f_y * (rel @ basis.y_e) / z
    lo_x = np.clip(np.floor(X.min(1) - 1) // tile, 0, tiles_x - 1).astype(int)
    hi_x = np.clip(np.floor(X.max(1) + 1) // tile, 0, tiles_x - 1).astype(int)
    lo_y = np.clip(np.floor(Y.min(1) - 1) // tile, 0, tiles_y - 1).astype(int)
    hi_y = np.clip(np.floor(Y.max(1) + 1) // tile, 0, tiles_y - 1).astype(int)
    inside = (X.max(1) >= 0) & (X.min(1) <= basis.width) & (Y.max(1) >= 0) & (Y.min(1) <= basis.height)
    for a, b, c, d in zip(lo_x[inside], hi_x[inside], lo_y[inside], hi_y[inside]):
        seen[c:d + 1, a:b + 1] = True
    return seen.reshape(-1)


class MirrorFrame:
    """The virtual cameras of one frame: ``chains`` (groups, side, tiles, triangles of the unfolded
    scene), ``mirrors`` (the kernel's record; None when no chain was worth a raster), ``nbytes``."""

    def __init__(self, scene, geom, data, fx, threads: int, bands: int, device: str,
                 margin: float = MIRROR_MARGIN_PX, stray_check: bool = True, caches: FrameCaches | None = None,
                 pool=None):
        """``caches``: the Renderer's for ``geom`` (planar groups, unfolded scenes, raster buffers kept
        across frames), or None for a frame of its own. ``margin`` and ``stray_check`` (tests only): the
        rasters' edge margin, and whether a ray that strays from its ideal line is traced; without both
        the decisions are not exact."""
        self.margin, self.stray_check = margin, stray_check
        caches = FrameCaches() if caches is None else caches
        cam = scene.camera
        basis = camera_basis(cam)
        kr = data.kr.numpy()
        group, planes = planar_groups(geom, kr.max(axis=1) > 0.0, caches.planar_groups)
        self.chains, self.mirrors, self.nbytes = [], None, 0
        if not len(planes):
            return
        eye = geom.eye_offset(cam.eye).astype(np.float64)
        faces = geom.indices_np.reshape(-1, 3)[: geom.triangle_count]
        group_tri = lambda g: geom.points_np[faces[group == g]].astype(np.float64)  # a mirror's triangles
        tile = RASTER_TILE
        tiles_x, tiles_y = -(-cam.width // tile), -(-cam.height // tile)
        spp = scene.render.spp if fx.supersampling else 1
        per_tile_samples = tile * tile * spp
        bounces = min(MAX_BOUNCES, scene.render.max_depth - 1)
        probed = self._probe(data, planes, basis, eye, group, tile, tiles_x, tiles_y, bounces, threads, bands, device, pool)
        candidates = []
        for chain, (where, side, probes) in probed.items():
            p = planes[list(chain)]
            seen = tiles_seen(group_tri(chain[0]), basis, eye, tile)
            if len(chain) == 2:
                # the level-1 rays leave the first mirror on the eye's side: the second, seen through it
                there = group_tri(chain[1])
                there = there[np.any(np.sign(p[0, :3] @ eye - p[0, 3]) * (there @ p[0, :3] - p[0, 3]) > 0.0, axis=1)]
                seen &= tiles_seen(reflect_points(there, p[0]), basis, eye, tile)
            seen &= where  # (deeper chains: where their probes went)
            if side != 0.0 and seen.any():
                candidates.append((chain, p, side, seen, probes))
        candidates.sort(key=lambda c: (-c[4], len(c[0])))  # the most rays first, a chain after its prefix
        budget = MAX_BYTES
        for groups, chain_planes, side, seen, _ in candidates:
            if len(self.chains) >= MAX_CHAINS:
                break
            if len(groups) > 1 and groups[:-1] not in [c["groups"] for c in self.chains]:
                continue
            stored = int(seen.sum()) * per_tile_samples * BYTES_PER_SAMPLE
            if stored > budget:
                continue
            unfolded = mirrored_geometry(geom, chain_planes, side, caches.mirrored)
            budget -= stored
            self.chains.append({"groups": groups, "planes": chain_planes, "side": side, "tiles": seen,
                                "unfolded": unfolded})
        if not self.chains:
            return
        self._rasterize(scene, geom, group, planes, fx, basis, eye, threads, bands, device, caches.raster_scratch, pool)

    @staticmethod
    def _probe(data, planes, basis, eye, group, tile, tiles_x, tiles_y, bounces, threads, bands, device, pool) -> dict:
        """{chain of groups: (the tiles where PROBES_PER_SIDE^2 traced camera rays per tile follow it, and
        their neighbours; the side of its last plane they start on; how many then hit something)}: which
        virtual cameras the frame needs, and where. A first bounce's side is the eye's; a later one's the
        probes' majority."""
        n = tiles_x * tiles_y * PROBES_PER_SIDE ** 2
        out = wp.empty((n, 2 + 2 * bounces), dtype=wp.int32, device=device)
        c, groups = camera_data(basis, eye), wp.array(group, dtype=wp.int32, device=device)
        planes32 = wp.array(planes.astype(np.float32), dtype=wp.vec4, device=device)
        launch_bands(probe_kernel, lambda first: [data, c, groups, planes32, tile, tiles_x, PROBES_PER_SIDE, bounces,
                                                  first, out], n, threads, bands, device, pool=pool)
        hits = out.numpy()
        found = {}
        for level in range(1, bounces + 1):
            rows = hits[hits[:, 2 * level - 1] >= 0]
            keys = rows[:, 1:2 * level:2]
            if not len(rows):
                break
            code = (keys.astype(np.int64) * (MAX_GROUPS ** np.arange(level, dtype=np.int64))).sum(axis=1)  # one int per chain
            codes, which = np.unique(code, return_inverse=True)
            for k in range(len(codes)):
                mine = rows[which == k]
                chain = tuple(int(g) for g in mine[0, 1:2 * level:2])
                where = np.zeros((tiles_y + 2, tiles_x + 2), bool)
                for dy in (0, 1, 2):  # the tiles probed, and their neighbours
                    for dx in (0, 1, 2):
                        where[mine[:, 0] // tiles_x + dy, mine[:, 0] % tiles_x + dx] = True
                p = planes[chain[0]]
                side = np.sign(p[:3] @ eye - p[3]) if level == 1 else np.sign(mine[:, 2 * level].sum())
                hitting = int((mine[:, -1] > level).sum())  # a ray that misses everything is cheap to trace too
                found[chain] = (where[1:-1, 1:-1].reshape(-1), float(side), hitting)
        return found

    def _rasterize(self, scene, geom, group, planes, fx, basis, eye, threads, bands, device, kept_scratch: dict, pool):
        cam, tile = scene.camera, RASTER_TILE
        tiles_x, tiles_y = -(-cam.width // tile), -(-cam.height // tile)
        n_tiles = tiles_x * tiles_y
        spp = scene.render.spp if fx.supersampling else 1
        per_tile = tile * tile * spp
        n_samples = cam.width * cam.height * spp
        C, G = len(self.chains), len(planes)
        tile_slot = np.full(C * n_tiles, -1, np.int32)
        first_chain = np.full(G, -2, np.int32)
        next_chain = np.full(C * G, -2, np.int32)
        slot = 0
        for c, chain in enumerate(self.chains):
            where = np.nonzero(chain["tiles"])[0]
            tile_slot[c * n_tiles + where] = slot + np.arange(len(where), dtype=np.int32)
            slot += len(where)
            groups = chain["groups"]
            if len(groups) == 1:
                first_chain[groups[0]] = c
        index = {chain["groups"]: c for c, chain in enumerate(self.chains)}
        for c, chain in enumerate(self.chains):
            groups = chain["groups"]
            if len(groups) > 1:
                next_chain[index[groups[:-1]] * G + groups[-1]] = c
        face = wp.empty(slot * per_tile, dtype=wp.int32, device=device)
        inv_depth = wp.empty(slot * per_tile, dtype=wp.float64, device=device)
        rival = wp.empty(slot * per_tile, dtype=wp.float64, device=device)
        tile_slot_wp = wp.array(tile_slot, dtype=wp.int32, device=device)
        flat = replace(fx, shadows=False, reflection=False)
        scratch, z_clip = kept_scratch.pop((n_samples, device), None), 0.0
        for c, chain in enumerate(self.chains):
            zb = ZBuffer(scene, chain["unfolded"], flat, device=device, margin=self.margin, fragments=scratch)
            zb.rasterize(threads, bands, tiles=chain["tiles"], pool=pool)
            scratch, z_clip = zb.fragments, max(z_clip, float(zb.camera.z_clip))
            stored = np.nonzero(chain["tiles"])[0].astype(np.int32)
            wp.launch(gather_kernel, dim=len(stored) * per_tile,
                      inputs=[scratch, tile_slot_wp, c, n_tiles, tiles_x, tile, spp, cam.width, cam.height,
                              chain["unfolded"].source, wp.array(stored, dtype=wp.int32, device=device), face,
                              inv_depth, rival], device=device)
            chain["triangles"] = chain["unfolded"].triangle_count
        kept_scratch.clear()
        kept_scratch[(n_samples, device)] = scratch  # clean again (gathered), for the next frame of this size
        m = Mirrors()
        m.group = wp.array(group, dtype=wp.int32, device=device)
        m.first_chain = wp.array(first_chain, dtype=wp.int32, device=device)
        m.next_chain = wp.array(next_chain, dtype=wp.int32, device=device)
        m.groups = G
        plane = np.zeros((C, MAX_BOUNCES, 4))
        for c, chain in enumerate(self.chains):
            plane[c, : len(chain["groups"])] = chain["planes"]
        m.plane = wp.array(plane.reshape(-1, 4), dtype=wp.vec4d, device=device)
        m.level = wp.array([len(ch["groups"]) for ch in self.chains], dtype=wp.int32, device=device)
        m.side = wp.array([ch["side"] for ch in self.chains], dtype=wp.float64, device=device)
        m.tile_slot, m.tiles, m.tiles_x, m.tile = tile_slot_wp, n_tiles, tiles_x, tile
        m.face, m.inv_depth, m.rival_inv_depth = face, inv_depth, rival
        m.camera = raster_camera(basis, z_clip, self.margin, eye)
        m.samples, m.k = spp, math.isqrt(scene.render.spp)
        cos_corner = basis.d_f / math.sqrt(basis.d_f ** 2 + (basis.h / 2.0) ** 2 + (basis.w / 2.0) ** 2)
        m.pixel_angle = wp.float64(basis.h / basis.height / basis.d_f * cos_corner ** 2 * (1.0 if self.stray_check else 1e30))
        m.decided = wp.zeros(cam.width * cam.height, dtype=wp.int32, device=device)
        self.mirrors = m
        self.nbytes = int(face.capacity + inv_depth.capacity + rival.capacity + tile_slot_wp.capacity
                          + sum(ch["unfolded"].nbytes for ch in self.chains))

    @property
    def stats(self) -> dict:
        return {"chains": [{"groups": list(map(int, ch["groups"])), "tiles": int(ch["tiles"].sum()),
                            "triangles": int(ch["unfolded"].triangle_count)} for ch in self.chains],
                "bytes": self.nbytes}
