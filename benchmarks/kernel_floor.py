"""The kernel at its floor: per scene, the smallest Warp kernel doing the same work as warprt's trace kernel
on the traced path, against that kernel, both on one thread; the floor's image is checked to be warprt's.

The floor is a bare kernel: one thread per pixel, row-major, one launch; the same camera rays, the same
wp.mesh_query_ray and any-hit queries, the same hit record (warprt's, with its error bound: the shadow
and reflection rays must start where warprt's do, or the images differ), the same Phong terms and
normals; no tiles, no bands, no ray counters, no AOV buffers, and a stack of local arrays only where
there is glass. warprt's kernel runs as render() launches it (bands of 8x8 tiles) with primary_query="raytrace",
shadow_query="bvh", reflection_query="bvh"; two more launches of it split the gap: one launch instead of bands,
then row-major order instead of tiles. All are alternated in one process; medians.

    python -m benchmarks.kernel_floor [--width 1024 --height 768 --repeat 5] [--scene NAME ...]
"""

from __future__ import annotations

import argparse
import functools
import statistics
import time
from pathlib import Path

import numpy as np

import warprt
from benchmarks.output import save
from warprt.geometry import Geometry, SceneData
from warprt.image import launch_bands
from warprt.kernels import (MAX_BOUNCES, CameraData, Fragments, Mirrors, beer, beer_forever, camera_data, camera_ray,
                            empty_aov_buffers, empty_record, fresnel_dielectric, init_warp, make_surface, make_trace_kernel,
                            offset_ray_origin, phong_diffuse, phong_specular, reflect, refract, stack_size, triangle,
                            unit_normal, wp)
from warprt.scene import camera_basis, resolve_effects

ROOT = Path(__file__).resolve().parent
REPO = ROOT.parent
SCENES = (None, "cornell", "seed", "mirrors", "bunny", "glass_cube")
TRACED = dict(primary_query="raytrace", shadow_query="bvh", reflection_query="bvh")
TILE = (8, 8)  # render()'s pixel order (image/renderer.PIXEL_TILE)
TARGET = 1.15
# What the floor does not write: an effect outside this set makes it refuse the scene, not differ.
REQUIRED = {"ambient", "diffuse", "specular", "shadows"}
SUPPORTED = REQUIRED | {"reflection", "smooth", "refraction", "absorption"}


@functools.cache
def floor_kernel(smooth: bool, reflection: bool, refraction: bool, absorption: bool, stack: int):
    """The bare kernel for one effect set (ambient, diffuse, specular and shadows always on)."""
    surface = make_surface(smooth)
    vec3s = wp.types.matrix(shape=(max(stack, 1), 3), dtype=float)
    ints = wp.types.vector(length=max(stack, 1), dtype=int)
    REFLECTION, REFRACTION, ABSORPTION = reflection, refraction, absorption

    @wp.kernel(module="unique", enable_backward=False)
    def floor(s: SceneData, c: CameraData, max_depth: int, image: wp.array(dtype=wp.vec3)):
        pixel = wp.tid()
        x = pixel % c.width
        row = pixel / c.width
        o = c.eye
        d = camera_ray(c, x, row, 0.5, 0.5)
        weight = wp.vec3(1.0)
        start = c.eye  # where the segment began, for Beer's law
        medium = s.eye_medium
        depth = int(0)
        color = wp.vec3(0.0)
        top = int(0)
        if wp.static(REFRACTION):  # the waiting rays, as local arrays written in place
            w_o = vec3s()
            w_d = vec3s()
            w_weight = vec3s()
            w_start = vec3s()
            w_depth = ints()
            w_medium = ints()
        while depth < max_depth:
            q = wp.mesh_query_ray(s.mesh, o, d, 1.0e30)
            if not q.result:
                if wp.static(ABSORPTION):
                    if medium >= 0:
                        weight = beer_forever(weight, s.absorption[medium])
                color = color + wp.cw_mul(weight, s.background)
            else:
                hit = surface(s, q.face, q.u, q.v, q.normal, d)
                m = hit.material
                if wp.static(ABSORPTION):
                    if medium >= 0:
                        weight = beer(weight, s.absorption[medium], wp.length(hit.p - start))
                local = wp.cw_mul(s.ambient, s.ka[m])
                for l in range(s.num_lights):
                    L = wp.normalize(s.light_pos[l] - hit.p)
                    n_dot_l = wp.dot(hit.n, L)
                    if n_dot_l > 0.0:
                        so = offset_ray_origin(hit.p, hit.err, hit.ng, L)
                        to_light = s.light_pos[l] - so
                        dist = wp.length(to_light)
                        if not wp.mesh_query_ray_anyhit(s.mesh, so, to_light / dist, dist):
                            lit = phong_diffuse(s.kd[m], n_dot_l) + phong_specular(s.ks[m], s.shininess[m], hit.n, L, -d,
                                                                                   n_dot_l)
                            local = local + wp.cw_mul(s.light_color[l], lit)
                color = color + wp.cw_mul(weight, local)
                level = depth + 1
                if wp.static(REFLECTION):
                    kr = s.kr[m]
                    if level < max_depth and wp.max(kr) > 0.0:
                        d = wp.normalize(reflect(d, hit.n))
                        o = offset_ray_origin(hit.p, hit.err, hit.ng, d)
                        weight = wp.cw_mul(weight, kr)
                        start = hit.p
                        depth = level
                        continue
                if wp.static(REFRACTION):
                    eta = s.ior[m]
                    if eta > 0.0 and level < max_depth:  # children only where they are traced
                        p0, p1, p2 = triangle(s, q.face)
                        entering = wp.dot(hit.ng, unit_normal(p0, p1, p2)) > 0.0
                        outward = hit.ng
                        eta_rel = eta
                        if not entering:
                            outward = -hit.ng
                            eta_rel = 1.0 / eta
                        n = hit.n
                        if wp.dot(n, hit.ng) < 0.0:
                            n = -n
                        if not (wp.dot(d, n) * wp.dot(d, hit.ng) > 0.0):
                            n = hit.ng
                        cos_i = -wp.dot(d, n)
                        F = fresnel_dielectric(wp.where(entering, cos_i, -cos_i), eta)
                        t, transmits = refract(d, n, eta_rel)
                        w_r = weight * F
                        w_t = wp.cw_mul(weight, s.transmittance[m]) * (1.0 - F)
                        has_r = wp.max(w_r) > 0.0
                        has_t = transmits and wp.max(w_t) > 0.0
                        if has_r or has_t:
                            d_r = wp.normalize(reflect(d, n))
                            if has_t:
                                if has_r:  # the reflected ray waits
                                    w_o[top] = offset_ray_origin(hit.p, hit.err, hit.ng, d_r)
                                    w_d[top] = d_r
                                    w_weight[top] = w_r
                                    w_start[top] = hit.p
                                    w_depth[top] = level
                                    w_medium[top] = wp.where(wp.dot(d_r, outward) < 0.0, m, -1)
                                    top += 1
                                d = wp.normalize(t)
                                weight = w_t
                            else:
                                d = d_r
                                weight = w_r
                            o = offset_ray_origin(hit.p, hit.err, hit.ng, d)
                            medium = wp.where(wp.dot(d, outward) < 0.0, m, -1)
                            start = hit.p
                            depth = level
                            continue
            if wp.static(REFRACTION):
                if top > 0:
                    top -= 1
                    o = w_o[top]
                    d = w_d[top]
                    weight = w_weight[top]
                    start = w_start[top]
                    depth = w_depth[top]
                    medium = w_medium[top]
                    continue
            break
        image[pixel] = color

    return floor


def no_mirrors() -> Mirrors:
    """Mirrors of no chain, as render() hands the kernel when reflection rays are traced."""
    m = Mirrors()
    ints = lambda: wp.zeros(1, dtype=wp.int32)  # noqa: E731
    m.group, m.first_chain, m.next_chain, m.level, m.tile_slot, m.face, m.decided = (ints() for _ in range(7))
    m.plane = wp.zeros(MAX_BOUNCES, dtype=wp.vec4d)
    m.side, m.inv_depth, m.rival_inv_depth = (wp.zeros(1, dtype=wp.float64) for _ in range(3))
    m.groups = m.tiles = m.tiles_x = m.tile = m.samples = m.k = 1
    m.pixel_angle = wp.float64(0.0)
    return m


def no_fragments() -> Fragments:
    f = Fragments()
    f.face = wp.empty(0, dtype=wp.int32)
    f.inv_depth = f.rival_inv_depth = wp.empty(0, dtype=wp.float64)
    f.uv = wp.empty(0, dtype=wp.vec2)
    return f


class Pair:
    """One scene at one size: warprt's trace kernel with render()'s inputs, and the floor's."""

    def __init__(self, scene):
        init_warp()
        fx = resolve_effects(scene)
        names = set(fx.names) | ({"light_model"} if fx.light_model else set())
        if not (REQUIRED <= names <= SUPPORTED):
            raise ValueError(f"the floor kernel writes effects {sorted(SUPPORTED)} with {sorted(REQUIRED)} on; "
                             f"this scene has {sorted(names)}")
        self.scene = scene
        self.renderer = warprt.Renderer(scene, threads=1, **TRACED)
        self.renderer.render()  # builds and keeps the geometry, compiles the variant
        self.reference = self.renderer.render()
        assert self.reference.stats.primary_query == "raytrace" and self.reference.stats.shadow_query == "bvh"
        self.geom = geom = Geometry(scene)  # kept: scene_data holds its mesh by id, freed with it
        cam = scene.camera
        self.n = cam.width * cam.height
        self.data = geom.scene_data(scene)
        self.c = camera_data(camera_basis(cam), geom.eye_offset(cam.eye))
        self.max_depth = scene.render.max_depth if fx.reflection or fx.refraction else 1
        stack = stack_size(scene.render.max_depth) if fx.refraction else 0
        self.warprt = make_trace_kernel(fx, stack=stack)
        self.floor = floor_kernel(fx.smooth, fx.reflection, fx.refraction, fx.absorption, stack)
        for k in (self.warprt, self.floor):
            wp.load_module(k.module, device="cpu")
        self.bands = self.reference.stats.bands  # render()'s for one thread
        self.frags, self.mirrors, self.aov = no_fragments(), no_mirrors(), empty_aov_buffers("cpu")
        self.rec = empty_record("cpu")
        self.image = wp.empty(self.n, dtype=wp.vec3)
        self.counts = wp.empty(self.n, dtype=wp.vec4i if fx.refraction else wp.vec3i)

    def run_floor(self) -> float:
        t = time.perf_counter()
        wp.launch(self.floor, dim=self.n, inputs=[self.data, self.c, self.max_depth, self.image], device="cpu")
        return time.perf_counter() - t

    def run_warprt(self, bands: int | None = None, tile=TILE) -> float:
        """warprt's kernel over ``bands`` launches on one thread (render()'s by default), pixels in ``tile`` order."""
        inputs = lambda first: [self.data, self.c, self.max_depth, 1, first, tile[0], tile[1], self.frags,  # noqa: E731
                                self.mirrors, self.aov, self.rec, self.image, self.counts]
        t = time.perf_counter()
        launch_bands(self.warprt, inputs, self.n, 1, bands or self.bands, "cpu")
        return time.perf_counter() - t

    def image_np(self) -> np.ndarray:
        cam = self.scene.camera
        return self.image.numpy().reshape(cam.height, cam.width, 3).copy()

    def difference(self) -> dict:
        """Where the floor's image differs from warprt.render's: pixels and the largest difference."""
        self.run_floor()
        floor = self.image_np()
        ref = self.reference.image
        diff = np.any(floor != ref, axis=-1)
        return {"identical": bool(not diff.any()), "pixels_differing": int(diff.sum()),
                "max_abs_diff": float(np.max(np.abs(floor - ref))) if diff.any() else 0.0}


def measure(scene, repeat: int = 5) -> dict:
    """Medians of ``repeat`` alternated runs: the floor, warprt's kernel as render() launches it, in one
    launch, in one launch row-major; and a warm frame of a Renderer on one thread. The ratios to the floor
    are medians of each repeat's own ratio, so a load that drifts between repeats cancels; the order
    is reversed every other repeat, so none always runs first."""
    pair = Pair(scene)
    row = pair.difference()
    runs = {"floor": pair.run_floor, "warprt": pair.run_warprt, "one_launch": lambda: pair.run_warprt(1),
            "row_major": lambda: pair.run_warprt(1, (scene.camera.width, 1)),
            "render": lambda: _render_seconds(pair.renderer)}
    times = {k: [] for k in runs}
    for j in range(repeat):
        for k in list(runs)[::1 if j % 2 == 0 else -1]:
            times[k].append(runs[k]())
    ratios = {f"{k}_ratio": statistics.median(t / f for t, f in zip(times[k], times["floor"]))
              for k in ("warprt", "one_launch", "row_major")}
    return {**row, **{k: statistics.median(v) for k, v in times.items()}, **ratios,
            "variant": pair.reference.stats.variant}


def ratio(row: dict, key: str = "warprt") -> float:
    """``key``'s time over the floor's: the median of the repeats' ratios where measured."""
    return row.get(f"{key}_ratio", row[key] / row["floor"])


def _render_seconds(renderer) -> float:
    t = time.perf_counter()
    renderer.render()
    return time.perf_counter() - t


def load(name, width, height):
    path = None if name in (None, "default") else REPO / "scenes" / f"{name}.toml"
    return warprt.load_scene(path, {"camera.width": width, "camera.height": height})


def run(width: int = 1024, height: int = 768, repeat: int = 5, only=None, log=print) -> dict:
    rows = []
    for name in only or SCENES:
        name = name or "default"
        row = {"scene": name, **measure(load(name, width, height), repeat)}
        rows.append(row)
        log(f"{name:<12} floor {row['floor'] * 1e3:6.0f} ms  warprt {row['warprt'] * 1e3:6.0f} ms  "
            f"{ratio(row):.2f}x  (one launch {ratio(row, 'one_launch'):.2f}x, row-major "
            f"{ratio(row, 'row_major'):.2f}x; render {row['render'] * 1e3:.0f} ms)"
            + ("" if row["identical"] else f"  IMAGE DIFFERS at {row['pixels_differing']} pixels"))
    return {"width": width, "height": height, "repeat": repeat, "rows": rows}


def target_row(data: dict) -> tuple[str, str, str]:
    ratios = [(ratio(r), r["scene"]) for r in data["rows"]]
    worst = max(ratios)
    same = all(r["identical"] for r in data["rows"])
    return (f"warprt's kernel within {TARGET:.2f}x of the floor on every scene (a bare Warp kernel doing the same work, "
            "one thread each)",
            f"{min(ratios)[0]:.2f}x to {worst[0]:.2f}x (worst: {worst[1]}); images "
            + ("identical" if same else "NOT identical: the floor is not valid"),
            "met" if same and worst[0] <= TARGET else "not met")


def report(data: dict) -> str:
    lines = ["## The kernel at its floor", "",
             f"{data['width']}x{data['height']}, warm, one thread, medians of {data['repeat']} alternated runs (the ratios: "
             "medians of each repeat's ratio to the floor). *floor*: a bare "
             "Warp kernel, one thread per pixel, row-major, one launch, with warprt's camera rays, hit record, queries and "
             "Phong terms (and local arrays for the ray tree where there is glass); its image is checked against "
             "`warprt.render`'s. *warprt*: warprt's trace kernel as `render(primary_query=\"raytrace\", shadow_query=\"bvh\", "
             "reflection_query=\"bvh\", threads=1)` launches it (bands of 8x8 tiles); *one launch*: the same kernel in one "
             "launch; *row-major*: one launch, pixels row-major (the floor's order); *render*: the whole `warprt.render`. "
             "Regenerate: `python -m benchmarks.kernel_floor`.", "",
             "| scene | floor (s) | warprt kernel (s) | ratio | one launch | row-major | render (s) | image |",
             "|---|---:|---:|---:|---:|---:|---:|---|"]
    for r in data["rows"]:
        f = r["floor"]
        same = "identical" if r["identical"] else f"{r['pixels_differing']} pixels differ (max {r['max_abs_diff']:.2g})"
        lines.append(f"| {r['scene']} | {f:.3f} | {r['warprt']:.3f} | {ratio(r):.2f}x | {ratio(r, 'one_launch'):.2f}x "
                     f"| {ratio(r, 'row_major'):.2f}x | {r['render']:.3f} | {same} |")
    return "\n".join(lines)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--width", type=int, default=1024)
    ap.add_argument("--height", type=int, default=768)
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--quick", action="store_true", help="128x96, one repeat: a smoke run")
    ap.add_argument("--scene", action="append", help="only these scenes (stems, or default)")
    ap.add_argument("-o", "--output", default=str(ROOT / "results" / "kernel_floor.md"))
    args = ap.parse_args(argv)
    size = (128, 96) if args.quick else (args.width, args.height)
    data = run(*size, 1 if args.quick else args.repeat, args.scene)
    print(f"wrote {save(args.output, data, report(data))}")


if __name__ == "__main__":
    main()
