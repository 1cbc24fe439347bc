"""Where shadow-ray time goes: the share of warprt's shadow rays that are occluded, and what the
occluded and the unoccluded ones cost, per scene. It decides whether caching the last occluder pays.

    python -m benchmarks.shadow_rays [--width 1024 --height 768]   -> benchmarks/results/shadow_rays.md (+ .json)

The rays are the renderer's own: each pixel centre's primary hit, shaded with the renderer's surface
and its error-bound offset, one shadow ray towards every light with n.L > 0. Each set is then cast
alone with wp.mesh_query_ray_anyhit on one thread (median of 5).
"""

from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

import numpy as np

from benchmarks.output import save
from warprt.geometry import Geometry, SceneData
from warprt.kernels import CameraData, camera_data, camera_ray, init_warp, make_surface, offset_ray_origin, wp
from warprt.scene import camera_basis, load_scene

ROOT = Path(__file__).resolve().parent
REPO = ROOT.parent
surface = make_surface(True)


@wp.kernel
def shadow_rays(s: SceneData, c: CameraData, origins: wp.array(dtype=wp.vec3), dirs: wp.array(dtype=wp.vec3),
                dists: wp.array(dtype=float)):
    """For pixel i and light l, the shadow ray the tracer would spawn (dists = -1 where it spawns none)."""
    i = wp.tid()
    d = camera_ray(c, i % c.width, i / c.width, 0.5, 0.5)
    q = wp.mesh_query_ray(s.mesh, c.eye, d, 1.0e30)
    for l in range(s.num_lights):
        k = i * s.num_lights + l
        dists[k] = -1.0
        if q.result:
            hit = surface(s, q.face, q.u, q.v, q.normal, d)
            L = wp.normalize(s.light_pos[l] - hit.p)
            if wp.dot(hit.n, L) > 0.0:
                o = offset_ray_origin(hit.p, hit.err, hit.ng, L)
                to_light = s.light_pos[l] - o
                dist = wp.length(to_light)
                origins[k] = o
                dirs[k] = to_light / dist
                dists[k] = dist


@wp.kernel
def any_hit(mesh: wp.uint64, origins: wp.array(dtype=wp.vec3), dirs: wp.array(dtype=wp.vec3),
            dists: wp.array(dtype=float), blocked: wp.array(dtype=wp.int32)):
    i = wp.tid()
    blocked[i] = wp.where(wp.mesh_query_ray_anyhit(mesh, origins[i], dirs[i], dists[i]), 1, 0)


def cast(mesh, o: np.ndarray, d: np.ndarray, t: np.ndarray, repeat: int) -> tuple[float, np.ndarray]:
    """Median seconds to cast the rays on one thread, and which were blocked."""
    args = [wp.array(o, dtype=wp.vec3), wp.array(d, dtype=wp.vec3), wp.array(t, dtype=float)]
    blocked = wp.zeros(len(t), dtype=wp.int32)
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        wp.launch(any_hit, dim=len(t), inputs=[mesh.id, *args, blocked])
        wp.synchronize()
        times.append(time.perf_counter() - start)
    return statistics.median(times), blocked.numpy().astype(bool)


def run(width: int = 1024, height: int = 768, repeat: int = 5, scenes=None) -> dict:
    init_warp()
    rows = []
    for path in scenes or sorted((REPO / "scenes").glob("*.toml")):
        scene = load_scene(path).with_camera(width=width, height=height)
        geom = Geometry(scene)
        n = width * height * geom.data.num_lights
        o, d, t = wp.zeros(n, dtype=wp.vec3), wp.zeros(n, dtype=wp.vec3), wp.full(n, -1.0, dtype=float)
        wp.launch(shadow_rays, dim=width * height, inputs=[geom.data, camera_data(camera_basis(scene.camera), geom.eye_offset(scene.camera.eye)),
                                                         o, d, t])
        keep = t.numpy() > 0.0
        if not keep.any():  # no lit term (glass_slab): no shadow rays to time
            continue
        o, d, t = o.numpy()[keep], d.numpy()[keep], t.numpy()[keep]
        total, blocked = cast(geom.mesh, o, d, t, repeat)
        occluded, _ = cast(geom.mesh, o[blocked], d[blocked], t[blocked], repeat)
        free, _ = cast(geom.mesh, o[~blocked], d[~blocked], t[~blocked], repeat)
        rows.append({"scene": Path(path).stem, "shadow_rays": int(len(t)), "occluded": int(blocked.sum()),
                     "all_s": total, "occluded_s": occluded, "free_s": free})
        print(f"{rows[-1]['scene']}: {blocked.mean():.1%} occluded, {occluded / total:.1%} of the time", flush=True)
    return {"width": width, "height": height, "repeat": repeat, "rows": rows}


def report(data: dict) -> str:
    lines = [
        "## Shadow rays: occluded and unoccluded",
        "",
        f"The renderer's own shadow rays from every pixel centre's first hit at {data['width']}x{data['height']}, "
        f"cast alone with `wp.mesh_query_ray_anyhit` on one thread (median of {data['repeat']}). Regenerate: "
        "`python -m benchmarks.shadow_rays`.",
        "",
        "| scene | shadow rays | occluded | share of shadow time | ns per occluded ray | ns per unoccluded ray |",
        "|---|---:|---:|---:|---:|---:|",
    ]
    for r in data["rows"]:
        free = r["shadow_rays"] - r["occluded"]
        lines.append(f"| {r['scene']} | {r['shadow_rays']:,} | {r['occluded'] / r['shadow_rays']:.1%} "
                     f"| {r['occluded_s'] / r['all_s']:.1%} | {1e9 * r['occluded_s'] / max(r['occluded'], 1):.0f} "
                     f"| {1e9 * r['free_s'] / max(free, 1):.0f} |")
    return "\n".join(lines)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--width", type=int, default=1024)
    ap.add_argument("--height", type=int, default=768)
    ap.add_argument("-o", "--output", default=str(ROOT / "results" / "shadow_rays.md"))
    args = ap.parse_args(argv)
    data = run(args.width, args.height)
    print(f"wrote {save(args.output, data, report(data))}")


if __name__ == "__main__":
    main()
