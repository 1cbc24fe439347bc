"""Raw ray casting: closest-hit and any-hit rays per second per core, warprt's Warp BVH queries
against Mitsuba 3's ray_intersect_preliminary / ray_test (Embree underneath), on the same meshes.

    python -m benchmarks.raycast [--max-subdiv 8]   -> benchmarks/results/raycast.md (+ .json)
"""

from __future__ import annotations

import argparse
import os
import statistics
import time
from pathlib import Path

import numpy as np

from benchmarks.output import save
from warprt.image import bands_of
from warprt.kernels import init_warp, wp  # Warp, quiet
from warprt.scene import shapes

os.environ.setdefault("DRJIT_LIBLLVM_PATH", "/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1")
ROOT = Path(__file__).resolve().parent
RES = 512  # a 512x512 pinhole camera's primary rays


@wp.kernel
def closest_hit(mesh: wp.uint64, dirs: wp.array(dtype=wp.vec3), first: int, t_out: wp.array(dtype=float)):
    i = first + wp.tid()
    q = wp.mesh_query_ray(mesh, wp.vec3(0.0), dirs[i], 1.0e30)
    t_out[i] = wp.where(q.result, q.t, -1.0)


@wp.kernel
def any_hit(mesh: wp.uint64, dirs: wp.array(dtype=wp.vec3), first: int, t_out: wp.array(dtype=float)):
    i = first + wp.tid()
    t_out[i] = wp.where(wp.mesh_query_ray_anyhit(mesh, wp.vec3(0.0), dirs[i], 1.0e30), 1.0, -1.0)


def camera_dirs(res: int, fovy_deg: float = 40.0) -> np.ndarray:
    """Unit directions of a pinhole at the origin looking down -z."""
    h = 2 * np.tan(np.radians(fovy_deg) / 2)
    x = (np.arange(res) + 0.5) / res - 0.5
    y = ((np.arange(res) + 0.5) / res - 0.5)[::-1]
    d = np.stack(np.broadcast_arrays(h * x[None, :], h * y[:, None], -np.ones((res, res))), -1).reshape(-1, 3)
    return (d / np.linalg.norm(d, axis=1, keepdims=True)).astype(np.float32)


def time_warp(kernel, mesh, dirs, threads, repeat):
    from concurrent.futures import ThreadPoolExecutor

    n = dirs.shape[0]
    out = wp.empty(n, dtype=float, device="cpu")
    ranges = bands_of(n, 16 if threads > 1 else 1)
    run = lambda r: wp.launch(kernel, dim=r[1], inputs=[mesh.id, dirs, r[0], out], device="cpu")
    wp.load_module(kernel.module, device="cpu")
    run((0, n))
    times = []
    with ThreadPoolExecutor(max_workers=threads) as pool:
        for _ in range(repeat):
            t = time.perf_counter()
            list(pool.map(run, ranges)) if threads > 1 else run((0, n))
            times.append(time.perf_counter() - t)
    return statistics.median(times), out.numpy().copy()


def time_mitsuba(vertices, faces, dirs_np, threads, repeat):
    import drjit as dr
    import mitsuba as mi

    mi.set_variant("llvm_ad_rgb")
    dr.set_thread_count(threads)
    mesh = mi.Mesh("m", len(vertices), len(faces))
    params = mi.traverse(mesh)
    params["vertex_positions"] = mi.Float(vertices.astype(np.float32).ravel())
    params["faces"] = mi.UInt32(faces.astype(np.uint32).ravel())
    params.update()
    scene = mi.load_dict({"type": "scene", "m": mesh})
    o = mi.Point3f(0.0, 0.0, 0.0)
    d = mi.Vector3f(mi.Float(dirs_np[:, 0]), mi.Float(dirs_np[:, 1]), mi.Float(dirs_np[:, 2]))
    dr.eval(d)
    ray = mi.Ray3f(o, d)
    result = {}
    for name, fn in (("closest", lambda: scene.ray_intersect_preliminary(ray).t), ("any", lambda: scene.ray_test(ray))):
        r = fn()
        dr.eval(r)
        dr.sync_thread()
        times = []
        for _ in range(repeat):
            t = time.perf_counter()
            r = fn()
            dr.eval(r)
            dr.sync_thread()
            times.append(time.perf_counter() - t)
        result[name] = (statistics.median(times), np.asarray(r))
    dr.set_thread_count(os.cpu_count() or 2)
    return result


def run(max_subdiv: int, repeat: int) -> dict:
    init_warp()
    dirs_np = camera_dirs(RES)
    dirs = wp.array(dirs_np, dtype=wp.vec3, device="cpu")
    rows = []
    for subdiv in range(2, max_subdiv + 1):
        v, f = shapes.sphere(1.0, subdiv)
        v = v + [0.0, 0.0, -3.0]  # fills most of a 40-degree view from the origin
        mesh = wp.Mesh(points=wp.array(v.astype(np.float32), dtype=wp.vec3), indices=wp.array(f.ravel().astype(np.int32), dtype=wp.int32))
        row = {"triangles": len(f), "rays": len(dirs_np)}
        for threads in (1, 2):
            tc, t_warp = time_warp(closest_hit, mesh, dirs, threads, repeat)
            ta, a_warp = time_warp(any_hit, mesh, dirs, threads, repeat)
            mi_res = time_mitsuba(v, f, dirs_np, threads, repeat)
            row[f"warp_closest_{threads}t"] = len(dirs_np) / tc
            row[f"warp_any_{threads}t"] = len(dirs_np) / ta
            row[f"mitsuba_closest_{threads}t"] = len(dirs_np) / mi_res["closest"][0]
            row[f"mitsuba_any_{threads}t"] = len(dirs_np) / mi_res["any"][0]
        # Both engines must agree on which rays hit, or the race is not the same race.
        hit_w = t_warp > 0
        hit_m = np.isfinite(mi_res["closest"][1]) & (mi_res["closest"][1] < 1e30)
        row["hit_agreement"] = float((hit_w == hit_m).mean())
        row["t_max_rel_diff"] = float(np.max(np.abs(t_warp[hit_w & hit_m] - mi_res["closest"][1][hit_w & hit_m]) / t_warp[hit_w & hit_m]))
        rows.append(row)
        print(f"{len(f):>9,} tris  warp {row['warp_closest_1t'] / 1e6:5.2f} M/s/core  mitsuba {row['mitsuba_closest_1t'] / 1e6:5.2f} M/s (1 thread)  agree {row['hit_agreement']:.5f}", flush=True)
    return {"resolution": RES, "rows": rows}


def report(data: dict) -> str:
    lines = [
        "# Raw ray casting: Warp's BVH queries against Mitsuba 3 / Embree",
        "",
        f"{data['resolution']}x{data['resolution']} primary rays from a pinhole at the origin into an icosphere of radius 1 at "
        "distance 3 (about 60% of the rays hit). Closest hit: `wp.mesh_query_ray` vs `Scene.ray_intersect_preliminary`; "
        "any hit: `wp.mesh_query_ray_anyhit` vs `Scene.ray_test`, Mitsuba `llvm_ad_rgb` with Dr.Jit's thread count set to the "
        "same number of threads. Million rays per second, median of the repeats. Regenerate: `python -m benchmarks.raycast`.",
        "",
        "| triangles | Warp closest 1t | Mitsuba closest 1t | ratio | Warp any 1t | Mitsuba any 1t | ratio | Warp closest 2t | Mitsuba closest 2t | hit agreement |",
        "|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for r in data["rows"]:
        m = lambda k: f"{r[k] / 1e6:.2f}"
        lines.append(f"| {r['triangles']:,} | {m('warp_closest_1t')} | {m('mitsuba_closest_1t')} | {r['warp_closest_1t'] / r['mitsuba_closest_1t']:.2f} "
                     f"| {m('warp_any_1t')} | {m('mitsuba_any_1t')} | {r['warp_any_1t'] / r['mitsuba_any_1t']:.2f} "
                     f"| {m('warp_closest_2t')} | {m('mitsuba_closest_2t')} | {r['hit_agreement']:.5f} |")
    return "\n".join(lines)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--max-subdiv", type=int, default=8, help="icosphere subdivisions up to this (8: 1.3M triangles)")
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("-o", "--output", default=str(ROOT / "results" / "raycast.md"))
    args = ap.parse_args()
    data = run(args.max_subdiv, args.repeat)
    save(args.output, data, report(data))
    print(report(data))


if __name__ == "__main__":
    main()
