"""Frames per second of a many-frame job against its length: a 320x240 orbit of scenes/seed.toml written as
PNGs by a Python loop calling warprt.render per frame, and by `warprt batch` (local workers, Ray, a cluster).

    python -m benchmarks.batch [--repeat 3] [--lengths 48,480,2400] [--quick]   -> benchmarks/results/batch.md (+ .json)

Each configuration runs in a fresh process, so nothing stays warm from the one before (Warp's kernel
cache on disk is warm: one untimed run of the job fills it first). Seconds are the whole call: for the
backends batch() from start to return (worker boot, frame checks, manifest included); Ray's own start
(ray.init, or the cluster's) is excluded and shown apart, as it is paid once per session. CPU use is the
user+sys time of the process and every process under it (workers, the fork server, Ray's) within those
seconds, read from /proc, over seconds x cores.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent
SCENE = ROOT.parent / "scenes" / "seed.toml"
LENGTHS = (48, 480, 2400)
CONFIGS = ("loop", "loop_reload", "local", "local_1", "local_2", "ray_1", "ray_2", "cluster_2", "mitsuba_loop")
# Past the first length: the loop, batch()'s own choice, and Ray with 2 actors (whose actors start fresh
# interpreters, a cost a long job spreads).
LONG_CONFIGS = ("loop", "local", "ray_2", "mitsuba_loop")
LABELS = {"loop": "Python loop: the scene loaded once, `with_camera` per frame, `warprt.render`, `write_image`",
          "loop_reload": "Python loop: `warprt.load_scene` per frame, `warprt.render`, `write_image`",
          "local": "local backend, its default workers x threads",
          "local_1": "local backend, 1 worker process", "local_2": "local backend, 2 worker processes",
          "ray_1": "Ray on this machine, 1 actor", "ray_2": "Ray on this machine, 2 actors",
          "cluster_2": "Ray, simulated 2-node cluster (1 CPU each)",
          "mitsuba_loop": "Mitsuba 3 script: the scene converted once (reference/), each frame's sensor, `mi.render` "
                          "with the same Whitted integrator, `write_bitmap` (llvm_ad_rgb, all cores)"}
JOB = """scene = "{scene}"
output = "frames/{{frame:04d}}.png"
[set]
"camera.width" = {width}
"camera.height" = {height}
[orbit]
frames = {frames}
"""
# Ray's simulated nodes: one CPU each, a small object store, no autoscaler or log monitor.
NODE = {"num_cpus": 1, "object_store_memory": 96 * 2**20, "no_monitor": True, "include_log_monitor": False}
POLL_S = 0.05  # how often the process tree's CPU times are read
LONG_ONCE = 500  # a longer job runs once: minutes a run, its start paid once, so it varies less


def run_one(config: str, job: Path, out: Path) -> dict:
    """One configuration, in this process: seconds (and their start and end on the monotonic clock, which
    the parent's CPU sampling shares), frames and where the time went."""
    os.environ.setdefault("RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER", "0")  # loopback only, read when Ray is imported
    os.environ.setdefault("RAY_USAGE_STATS_ENABLED", "0")
    import warprt
    from warprt.dataset import batch, check_scene, connect_ray, load_job
    from warprt.image import default_threads, write_image

    res = {"config": config}
    if config == "mitsuba_loop":
        return _mitsuba_loop(job, out, res)
    if config.startswith("loop"):
        j = load_job(job, out)
        base = check_scene(j)
        (out / "frames").mkdir(parents=True, exist_ok=True)
        t0 = time.perf_counter()
        res["start"] = time.monotonic()
        times, first, renderer = [], None, warprt.Renderer(base, threads=default_threads())
        for f in j.frames:  # one Renderer, as a user's loop would keep: its BVH reused while the mesh stays
            if config == "loop_reload":
                scene = warprt.load_scene(j.scene_path, f.overrides)
            else:
                scene = base.with_camera(eye=tuple(f.overrides["camera.eye"]))
            renderer.set_scene(scene)
            image, stats = renderer.render()
            write_image(out / f.outputs["color"], image)
            times.append(stats.times)
            first = first or time.perf_counter() - t0
        res.update(seconds=time.perf_counter() - t0, end=time.monotonic(), frames=len(j.frames), workers=1,
                   threads=default_threads(), first_frame_seconds=first, frame_ms=frame_ms(times))
        return res
    kind, _, workers = config.partition("_")
    cluster, address = None, None
    if kind in ("ray", "cluster"):
        import ray

        t = time.perf_counter()
        if kind == "ray":
            connect_ray(None)  # as --ray does; batch() finds it running
            address = "local"
        else:
            from ray.cluster_utils import Cluster

            cluster = Cluster(initialize_head=True, head_node_args={**NODE, "include_dashboard": False})
            cluster.add_node(**NODE)
            cluster.wait_for_nodes()
            address = cluster.address
        res["ray_start_seconds"] = time.perf_counter() - t
    first = []
    t0 = time.perf_counter()
    res["start"] = time.monotonic()
    result = batch(job, out, workers=int(workers) if workers else None, ray=address,
                   on_frame=lambda row: first or first.append(time.perf_counter() - t0))
    rows = result.rows
    res.update(seconds=time.perf_counter() - t0, end=time.monotonic(), frames=len(rows), workers=result.workers,
               threads=result.threads, render_seconds=result.render_seconds,
               boot_seconds=list(result.boot_seconds) or None, first_frame_seconds=first[0],
               nodes=len({r["worker"].get("node", r["worker"]["host"]) for r in rows}),
               frame_ms=frame_ms([r["stats"]["times"] for r in rows]))
    if kind in ("ray", "cluster"):
        import ray

        ray.shutdown()
        if cluster is not None:
            cluster.shutdown()
    return res


def _mitsuba_loop(job: Path, out: Path, res: dict) -> dict:
    """The orbit as a Mitsuba user's script renders it: the scene converted to Mitsuba once (its Embree BVH
    built once, as warprt's loop keeps its Renderer), then per frame the sensor at that frame's eye, a render
    with the reference's Whitted integrator (the same model) and the PNG written by Mitsuba."""
    from reference.mitsuba_whitted import Switches, mitsuba, mitsuba_scene
    from warprt.dataset import check_scene, load_job
    from warprt.scene import resolve_effects

    j = load_job(job, out)
    base = check_scene(j)
    (out / "frames").mkdir(parents=True, exist_ok=True)
    switches = Switches.for_effects(resolve_effects(base), base.render)
    t0 = time.perf_counter()
    res["start"] = time.monotonic()
    ms, first = mitsuba_scene(base, switches.smooth), None
    mi = mitsuba()[0]
    for f in j.frames:
        camera = base.with_camera(eye=tuple(f.overrides["camera.eye"])).camera
        image = ms.render(switches, camera=camera)
        mi.util.write_bitmap(str(out / f.outputs["color"]), image)
        first = first or time.perf_counter() - t0
    res.update(seconds=time.perf_counter() - t0, end=time.monotonic(), frames=len(j.frames), workers=1,
               threads=os.cpu_count(), first_frame_seconds=first, frame_ms={"bvh": 0.0, "trace": 0.0, "total": 0.0})
    return res


def frame_ms(times: list[dict]) -> dict:
    """Mean milliseconds per frame of the render phases that matter here (RenderStats.times)."""
    return {k: 1e3 * statistics.mean(t.get(k, 0.0) for t in times) for k in ("bvh", "trace", "total")}


def _tree_cpu(root: int) -> dict:
    """pid -> user+sys seconds of ``root`` and every process under it (Linux /proc)."""
    tick = os.sysconf("SC_CLK_TCK")
    parent, cpu = {}, {}
    for name in os.listdir("/proc"):
        if not name.isdigit():
            continue
        try:
            with open(f"/proc/{name}/stat", "rb") as f:
                fields = f.read().rsplit(b")", 1)[1].split()
        except OSError:
            continue  # gone meanwhile
        parent[int(name)] = int(fields[1])
        cpu[int(name)] = (int(fields[11]) + int(fields[12])) / tick
    tree, todo = set(), [root]
    while todo:
        p = todo.pop()
        tree.add(p)
        todo += [c for c, pp in parent.items() if pp == p and c not in tree]
    return {p: cpu[p] for p in tree if p in cpu}


def run_child(config: str, job: Path, out: Path, env=None) -> dict:
    """run_one in a fresh process, its process tree's CPU sampled every POLL_S: ``cpu_seconds`` is what the
    tree used between the run's start and end (a process exiting between two samples loses its last POLL_S)."""
    p = subprocess.Popen([sys.executable, "-m", "benchmarks.batch", "--one", config, "--job", str(job), "--out", str(out)],
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=ROOT.parent, env=env)
    samples = []  # (monotonic time, pid -> cpu seconds)
    while p.poll() is None:
        samples.append((time.monotonic(), _tree_cpu(p.pid)))
        time.sleep(POLL_S)
    stdout, stderr = p.communicate()
    if p.returncode:
        raise RuntimeError(f"{config} failed: {stderr[-2000:]}")
    r = json.loads(stdout.strip().splitlines()[-1])
    before = next((s for t, s in reversed(samples) if t <= r["start"]), {})
    used = {}
    for t, s in samples:
        if t <= r["end"]:
            used.update(s)  # the last sample within the run of each process
    r["cpu_seconds"] = sum(c - before.get(pid, 0.0) for pid, c in used.items())
    r["cores"] = len(os.sched_getaffinity(0))
    r["cpu_use"] = r["cpu_seconds"] / (r["seconds"] * r["cores"])
    return r


def run(lengths=LENGTHS, width: int = 320, height: int = 240, repeat: int = 3, quick: bool = False,
        configs=CONFIGS, log=print) -> dict:
    """Per job length, each configuration ``repeat`` times (once past LONG_ONCE frames; the loop and the
    default local backend only past the first length), alternated, each in a fresh process; the frames in a
    temporary folder."""
    if quick:
        lengths, width, height, repeat = (4, 8), 64, 48, 1
    results = []
    with tempfile.TemporaryDirectory(prefix="warprt-bench-batch-") as tmp:
        for n in lengths:
            job = Path(tmp) / f"orbit{n}.toml"
            job.write_text(JOB.format(scene=SCENE.as_posix(), width=width, height=height, frames=n))
            if n == lengths[0]:
                warm = subprocess.run([sys.executable, "-m", "warprt", "batch", str(job), "-o", str(Path(tmp) / "warm"),
                                       "-q"], capture_output=True, text=True)  # fills Warp's kernel cache
                if warm.returncode:
                    raise RuntimeError(f"warm-up run failed: {warm.stderr[-2000:]}")
            for rep in range(repeat if n <= LONG_ONCE else 1):
                for config in configs if n == lengths[0] else [c for c in configs if c in LONG_CONFIGS]:
                    load = os.getloadavg()[0]
                    r = run_child(config, job, Path(tmp) / f"{config}-{n}-{rep}")
                    r["load_before"] = load
                    results.append(r)
                    log(f"  {n:5d} frames {config:12s} {r['frames'] / r['seconds']:6.2f} frames/s ({r['seconds']:.1f} s, "
                        f"CPU {r['cpu_use']:.0%}" + (f", Ray start {r['ray_start_seconds']:.1f} s" if "ray_start_seconds" in r
                                                     else "") + ")")
    return {"lengths": list(lengths), "width": width, "height": height, "repeat": repeat, "scene": "scenes/seed.toml",
            "cores": len(os.sched_getaffinity(0)), "results": results}


def best(data: dict, frames: int) -> dict:
    """Per configuration, its fastest run at this job length (the one least disturbed by anything else)."""
    out = {}
    for r in data["results"]:
        if r["frames"] == frames and (r["config"] not in out or r["seconds"] < out[r["config"]]["seconds"]):
            out[r["config"]] = r
    return out


def ratios(data: dict) -> dict:
    """The targets' numbers. Per job length: the default local backend's frames/s over the loop's, and its
    CPU use; Ray's time (2 actors) over local's (2 workers: local_2, or the default local past the first
    length, where it is 2 x 1); and the local backend's frames/s over the Mitsuba script's (mitsuba_loop)."""
    out = {"local_over_loop": {}, "cpu_use": {}, "ray_over_local": {}, "local_over_mitsuba": {}}
    for n in data["lengths"]:
        b = best(data, n)
        if "loop" in b and "local" in b:
            out["local_over_loop"][n] = b["loop"]["seconds"] / b["local"]["seconds"]
            out["cpu_use"][n] = b["local"]["cpu_use"]
        if "mitsuba_loop" in b and "local" in b:  # frames per second: the Mitsuba script's time over local's
            out["local_over_mitsuba"][n] = b["mitsuba_loop"]["seconds"] / b["local"]["seconds"]
        local = b.get("local_2") or (b["local"] if "local" in b and b["local"]["workers"] == 2 else None)
        if "ray_2" in b and local:
            out["ray_over_local"][n] = b["ray_2"]["seconds"] / local["seconds"]
    return out


def report(data: dict) -> str:
    cores = data["cores"]
    lines = [
        "## Many frames: `warprt batch`",
        "",
        f"{data['width']}x{data['height']} orbits of {data['scene']} written as PNGs, {cores} cores; each configuration "
        f"in a fresh process, best of {data['repeat']} (median beside it; once past {LONG_ONCE} frames). Seconds are the whole call (worker boot, "
        "frame checks and manifest included); Ray's own start is apart. CPU use: user+sys of the process and all "
        f"under it within those seconds, over seconds x {cores} cores. Worker start: from batch() to a worker ready "
        "(scene loaded, kernels warm), the slowest worker; first frame: from the call to its first finished frame. "
        "Regenerate: `python -m benchmarks.batch`.",
        "",
        "| frames | configuration | frames/s | median frames/s | seconds | CPU use | workers x threads | worker start s | "
        "first frame s | Ray start s | ms per frame: BVH / trace / total |",
        "|---:|---|---:|---:|---:|---:|---|---:|---:|---:|---|",
    ]
    for n in data["lengths"]:
        b = best(data, n)
        for config in CONFIGS:
            if config not in b:
                continue
            r = b[config]
            runs = [x["frames"] / x["seconds"] for x in data["results"] if x["config"] == config and x["frames"] == n]
            boot = f"{max(r['boot_seconds']):.2f}" if r.get("boot_seconds") else ""
            ray_start = f"{r['ray_start_seconds']:.1f}" if "ray_start_seconds" in r else ""
            ms = r["frame_ms"]
            lines.append(f"| {n} | {LABELS[config]} | {r['frames'] / r['seconds']:.2f} | {statistics.median(runs):.2f} | "
                         f"{r['seconds']:.1f} | {r['cpu_use']:.0%} | {r['workers']} x {r['threads']} | {boot} | "
                         f"{r['first_frame_seconds']:.2f} | {ray_start} | {ms['bvh']:.0f} / {ms['trace']:.0f} / {ms['total']:.0f} |")
    q = ratios(data)
    lines += ["", "The local backend (its default workers x threads) against the loop: "
              + ", ".join(f"{x:.2f}x the frames per second at {n} frames (CPU use {q['cpu_use'][n]:.0%})"
                          for n, x in q["local_over_loop"].items()) + "."]
    if q["ray_over_local"]:
        lines[-1] += (" Ray on this machine (2 actors) against the local backend (2 workers): "
                      + ", ".join(f"{x:.2f}x its time at {n} frames" for n, x in q["ray_over_local"].items()) + ".")
    if q["local_over_mitsuba"]:
        lines[-1] += (" The local backend against a Mitsuba script rendering the same orbit with the same model: "
                      + ", ".join(f"{x:.2f}x its frames per second at {n} frames"
                                  for n, x in q["local_over_mitsuba"].items()) + ".")
    lines += [
        "",
        "On real machines: a cluster node renders with all its cores (here two simulated nodes share two), so "
        "frames per second grow with the nodes while the driver only sends small task records and receives stats; "
        "joining a cluster costs a few seconds once per session rather than the local `ray.init`; every node must "
        "read the scene file and write the output folder at the same path (a shared file system); and each worker "
        "keeps its scene and kernels warm, so only its first frame pays Warp's start and kernel loading. The BVH "
        "column is what each frame spends building geometry for its eye: every frame of an orbit while a BVH is "
        "built per eye, nothing once one is reused across eyes.",
    ]
    return "\n".join(lines)


def targets(data: dict, met) -> list[tuple]:
    """The Targets table's rows for batch: (target, measured, verdict); ``met(bool)`` words the verdict."""
    q = ratios(data)
    size = f"{data['width']}x{data['height']} orbit, {data['cores']} cores"
    rows = []
    for goal, n in ((1.0, data["lengths"][0]), (1.3, data["lengths"][1] if len(data["lengths"]) > 1 else None)):
        if n in q["local_over_loop"]:
            x = q["local_over_loop"][n]
            rows.append((f"`warprt batch`, local backend: >= {goal:.1f}x the frames per second of a Python loop calling "
                         f"`warprt.render`, {n} frames", f"{x:.2f}x ({n}-frame {size})", met(x >= goal)))
    if q["cpu_use"]:
        use = min(q["cpu_use"].values())
        rows.append(("`warprt batch`, local backend: CPU use >= 90% of the cores during the job",
                     ", ".join(f"{u:.0%} at {n} frames" for n, u in q["cpu_use"].items()), met(use >= 0.9)))
    for n, x in q["ray_over_local"].items():
        rows.append((f"`warprt batch --ray` on one machine: within 1.25x of the local backend's time, {n} frames",
                     f"{x:.2f}x (2 actors against 2 worker processes; Ray's start apart)", met(x <= 1.25)))
    for n, x in q["local_over_mitsuba"].items():
        rows.append((f"`warprt batch`, local backend: >= 1.0x the frames per second of a Mitsuba script rendering the "
                     f"same orbit (issue 37), {n} frames", f"{x:.2f}x ({n}-frame {size})", met(x >= 1.0)))
    return rows


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--lengths", default=",".join(map(str, LENGTHS)), help="job lengths in frames (default: %(default)s)")
    ap.add_argument("--quick", action="store_true", help="4 and 8 frames at 64x48, once: a smoke run")
    ap.add_argument("-o", "--output", default=str(ROOT / "results" / "batch.md"))
    ap.add_argument("--one", choices=CONFIGS, help=argparse.SUPPRESS)  # one configuration, in this process
    ap.add_argument("--job", help=argparse.SUPPRESS)
    ap.add_argument("--out", help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.one:
        print(json.dumps(run_one(args.one, Path(args.job), Path(args.out))))
        sys.stdout.flush()
        os._exit(0)  # Ray's and Warp's native teardown only costs time
    from benchmarks.output import save

    data = run(lengths=tuple(int(x) for x in args.lengths.split(",")), repeat=args.repeat, quick=args.quick)
    print(f"wrote {save(args.output, data, report(data))}")


if __name__ == "__main__":
    main()
