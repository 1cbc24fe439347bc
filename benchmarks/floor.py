"""The floor of a warm frame: the renderer's frame with every shadow and reflection answer free, so the
gap between it and the measured frame is what those queries still cost.

A copy of the trace kernel's loop (the renderer's own camera, hit record, Phong terms, offsets and
first-hit path) runs twice: once answering every shadow and reflection ray with Warp's queries and
recording the answers, then reading them back instead of querying. Its image must be warprt's to the
bit (checked), so it does the renderer's work less the queries.

    python -m benchmarks.floor [--width 1024 --height 768] [--scene NAME ...]
"""

from __future__ import annotations

import argparse
import functools
import math
import statistics
import time
from pathlib import Path

import numpy as np

import warprt
from benchmarks.output import save
from warprt.geometry import Geometry, SceneData
from warprt.image import ZBuffer, launch_bands
from warprt.kernels import (CameraData, Fragments, camera_data, camera_ray, init_warp, make_surface, offset_ray_origin,
                            phong_diffuse, phong_specular, query_normal, reflect, sample_offset, tile_order_pixel,
                            triangle, uncertain, woop_hit, wp)
from warprt.scene import camera_basis, resolve_effects

ROOT = Path(__file__).resolve().parent
REPO = ROOT.parent
TILE = (8, 8)  # the renderer's pixel order (image/renderer.PIXEL_TILE)


@wp.struct
class Answers:
    shadow: wp.array(dtype=wp.int32)  # per sample and ray level: bit l set where light l's shadow ray is blocked
    face: wp.array(dtype=wp.int32)  # per sample and ray level >= 1: the reflection ray's hit, -1 none
    uv: wp.array(dtype=wp.vec2)
    normal: wp.array(dtype=wp.vec3)


@functools.cache
def floor_kernel(fx, raster: bool, replay: bool):
    """The frame, answering shadow and reflection rays with the queries (recording them), or with
    ``replay`` from the record."""
    surface = make_surface(fx.smooth)
    AMBIENT, DIFFUSE, SPECULAR, SHADOWS = fx.ambient, fx.diffuse, fx.specular, fx.shadows
    REFLECTION, SUPERSAMPLING, RASTER, REPLAY = fx.reflection, fx.supersampling, raster, replay

    @wp.kernel(module="unique", enable_backward=False)
    def frame(s: SceneData, c: CameraData, max_depth: int, k: int, first: int, frags: Fragments, a: Answers,
              image: wp.array(dtype=wp.vec3)):
        i = first + wp.tid()
        xy = tile_order_pixel(i, c.width, c.height, 8, 8)
        x = xy[0]
        row = xy[1]
        pixel = row * c.width + x
        total = wp.vec3(0.0)
        samples = int(1)
        if wp.static(SUPERSAMPLING):
            samples = k * k
        for sample in range(samples):
            offset = wp.vec2(0.5, 0.5)
            if wp.static(SUPERSAMPLING):
                offset = sample_offset(sample, k)
            o = c.eye
            d = camera_ray(c, x, row, offset[0], offset[1])
            weight = wp.vec3(1.0)
            color = wp.vec3(0.0)
            depth = int(0)
            n_s = pixel * samples + sample
            while depth < max_depth:
                slot = n_s * max_depth + depth
                f = int(-1)
                u = float(0.0)
                v = float(0.0)
                face_normal = wp.vec3(0.0)
                done = False
                if depth == 0:
                    if wp.static(RASTER):
                        if not uncertain(frags.inv_depth[n_s], frags.rival_inv_depth[n_s]):
                            done = True
                            f = frags.face[n_s]
                            if f >= 0:
                                p0, p1, p2 = triangle(s, f)
                                h = woop_hit(o, d, p0, p1, p2)
                                if h[0] >= 0.0:
                                    u = h[1]
                                    v = h[2]
                                    face_normal = query_normal(p0, p1, p2)
                                else:
                                    done = False
                                    f = -1
                elif wp.static(REPLAY):
                    done = True
                    f = a.face[slot]
                    uv = a.uv[slot]
                    u = uv[0]
                    v = uv[1]
                    face_normal = a.normal[slot]
                if not done:
                    q = wp.mesh_query_ray(s.mesh, o, d, 1.0e30)
                    if q.result:
                        f = q.face
                        u = q.u
                        v = q.v
                        face_normal = q.normal
                    if not wp.static(REPLAY) and depth > 0:
                        a.face[slot] = f
                        a.uv[slot] = wp.vec2(u, v)
                        a.normal[slot] = face_normal
                if f < 0:
                    color = color + wp.cw_mul(weight, s.background)
                    break
                hit = surface(s, f, u, v, face_normal, d)
                m = hit.material
                local = wp.vec3(0.0)
                if wp.static(AMBIENT):
                    local = wp.cw_mul(s.ambient, s.ka[m])
                if wp.static(DIFFUSE or SPECULAR):
                    blocked = int(0)
                    if wp.static(REPLAY and SHADOWS):
                        blocked = a.shadow[slot]
                    for l in range(s.num_lights):
                        L = wp.normalize(s.light_pos[l] - hit.p)
                        n_dot_l = wp.dot(hit.n, L)
                        if n_dot_l > 0.0:
                            visible = True
                            if wp.static(SHADOWS):
                                if wp.static(REPLAY):
                                    visible = (blocked & (1 << l)) == 0
                                else:
                                    so = offset_ray_origin(hit.p, hit.err, hit.ng, L)
                                    to_light = s.light_pos[l] - so
                                    dist = wp.length(to_light)
                                    if wp.mesh_query_ray_anyhit(s.mesh, so, to_light / dist, dist):
                                        visible = False
                                        blocked = blocked | (1 << l)
                            if visible:
                                lit = wp.vec3(0.0)
                                if wp.static(DIFFUSE):
                                    lit = lit + phong_diffuse(s.kd[m], n_dot_l)
                                if wp.static(SPECULAR):
                                    lit = lit + phong_specular(s.ks[m], s.shininess[m], hit.n, L, -d, n_dot_l)
                                local = local + wp.cw_mul(s.light_color[l], lit)
                    if wp.static(SHADOWS and not REPLAY):
                        a.shadow[slot] = blocked
                color = color + wp.cw_mul(weight, local)
                depth += 1
                if wp.static(REFLECTION):
                    kr = s.kr[m]
                    if depth < max_depth and wp.max(kr) > 0.0:
                        weight = wp.cw_mul(weight, kr)
                        d = wp.normalize(reflect(d, hit.n))
                        o = offset_ray_origin(hit.p, hit.err, hit.ng, d)
                        continue
                break
            total = total + color
        image[pixel] = total / float(samples)

    return frame


class Floor:
    """One scene at one size, warm, as warprt.render sets it up (the cached geometry and first-hit policy)."""

    def __init__(self, scene):
        init_warp()
        self.scene = scene
        self.renderer = warprt.Renderer(scene)
        self.renderer.render()  # the first two frames build and keep what the next frames reuse
        reference = self.renderer.render()
        self.reference = reference
        self.raster = reference.stats.primary_query == "zbuffer"
        self.fx = resolve_effects(scene)
        self.geom = Geometry(scene)
        self.data = self.geom.scene_data(scene)
        cam = scene.camera
        self.k = math.isqrt(scene.render.spp)
        samples = cam.width * cam.height * (self.k * self.k if self.fx.supersampling else 1)
        self.max_depth = scene.render.max_depth if self.fx.reflection else 1
        n = samples * self.max_depth
        a = Answers()
        a.shadow, a.face = wp.zeros(n, dtype=wp.int32), wp.zeros(n, dtype=wp.int32)
        a.uv, a.normal = wp.zeros(n, dtype=wp.vec2), wp.zeros(n, dtype=wp.vec3)
        self.answers = a
        self.c = camera_data(camera_basis(cam), self.geom.eye_offset(cam.eye))
        self.image = wp.empty(cam.width * cam.height, dtype=wp.vec3)
        self.threads = reference.stats.threads
        self.bands = reference.stats.bands

    def frame(self, replay: bool) -> tuple[np.ndarray, float]:
        """(image, seconds) of one frame: its Z-buffer pass where the renderer has one, then the kernel."""
        kernel = floor_kernel(self.fx, self.raster, replay)
        wp.load_module(kernel.module, device="cpu")
        t = time.perf_counter()
        frags = None
        if self.raster:
            from dataclasses import replace

            zb = ZBuffer(self.scene, self.geom, replace(self.fx, shadows=False, reflection=False))
            zb.rasterize(self.threads, self.bands)
            frags = zb.fragments
        else:
            frags = Fragments()
            frags.face = wp.empty(0, dtype=wp.int32)
            frags.inv_depth = frags.rival_inv_depth = wp.empty(0, dtype=wp.float64)
            frags.uv = wp.empty(0, dtype=wp.vec2)
        cam = self.scene.camera
        launch_bands(kernel, lambda first: [self.data, self.c, self.max_depth, self.k, first, frags, self.answers,
                                            self.image], cam.width * cam.height, self.threads, self.bands, "cpu")
        image = self.image.numpy().reshape(cam.height, cam.width, 3).copy()
        return image, time.perf_counter() - t


def measure(scene, repeat: int = 3) -> dict:
    """The warm frame as warprt.render does it, and its floor, each the median of ``repeat``."""
    floor = Floor(scene)
    recorded, _ = floor.frame(replay=False)
    replayed, _ = floor.frame(replay=True)
    same = bool(np.array_equal(recorded, floor.reference.image) and np.array_equal(replayed, floor.reference.image))
    warm, free = [], []
    for _ in range(repeat):  # alternated, so both see the same machine
        t = time.perf_counter()
        floor.renderer.render()
        warm.append(time.perf_counter() - t)
        free.append(floor.frame(replay=True)[1])
    return {"warm": statistics.median(warm), "floor": statistics.median(free), "identical": same,
            "variant": floor.reference.stats.variant}


def run(width: int = 1024, height: int = 768, repeat: int = 3, only=None) -> dict:
    rows = []
    for path in [None] + sorted((REPO / "scenes").glob("*.toml")):
        name = "default" if path is None else path.stem
        if only and name not in only:
            continue
        scene = warprt.load_scene(path, {"camera.width": width, "camera.height": height})
        row = {"scene": name, **measure(scene, repeat)}
        rows.append(row)
        print(f"{name:<16} warm {row['warm'] * 1e3:.0f} ms, floor {row['floor'] * 1e3:.0f} ms"
              f"{'' if row['identical'] else '  (image differs from warprt: floor not valid)'}", flush=True)
    return {"width": width, "height": height, "repeat": repeat, "rows": rows}


def report(data: dict) -> str:
    lines = ["## The floor: a frame whose shadow and reflection answers are free", "",
             f"{data['width']}x{data['height']}, warm, median of {data['repeat']}: warprt's frame as `warprt.render` makes it, and the "
             "same frame (the renderer's loop, its first hits, shading and ray spawning) with every shadow and reflection "
             "answer read from a record instead of queried; its image is checked to be warprt's to the bit. Regenerate: "
             "`python -m benchmarks.floor`.", "",
             "| scene | warm frame (s) | floor (s) | queries' share of the frame | identical |", "|---|---:|---:|---:|---|"]
    for r in data["rows"]:
        lines.append(f"| {r['scene']} | {r['warm']:.3f} | {r['floor']:.3f} | {1 - r['floor'] / r['warm']:.0%} | "
                     f"{'yes' if r['identical'] else 'no'} |")
    return "\n".join(lines)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--width", type=int, default=1024)
    ap.add_argument("--height", type=int, default=768)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--scene", action="append", help="only these scenes (stems, or default)")
    ap.add_argument("-o", "--output", default=str(ROOT / "results" / "floor.md"))
    args = ap.parse_args(argv)
    data = run(args.width, args.height, args.repeat, args.scene)
    print(f"wrote {save(args.output, data, report(data))}")


if __name__ == "__main__":
    main()
