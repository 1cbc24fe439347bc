"""What each effect costs: every scene rendered with its full effect set, then with each effect
switched off, and along the seed's Figure 6 levels; times as ratios to the full render.

    python -m benchmarks.effects [--width 512 --height 384 --repeat 5]   -> benchmarks/results/effects.md
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import time
from pathlib import Path

from dataclasses import replace

import warprt
from warprt.scene import Material, resolve_effects
from warprt.geometry import Geometry

ROOT = Path(__file__).resolve().parent
FIG6 = [
    ("(a) ambient", ["ambient", "smooth", "supersampling"], 1),
    ("(b) + diffuse", ["ambient", "diffuse", "smooth", "supersampling"], 1),
    ("(c) + specular", ["ambient", "diffuse", "specular", "smooth", "supersampling"], 1),
    ("(d) + shadows", ["ambient", "diffuse", "specular", "shadows", "smooth", "supersampling"], 1),
    ("(e) reflection level 1", None, 2),
    ("(f) reflection level 2", None, 3),
]
# The refraction level: the seed's scene with its sphere made of clear glass (glass_sphere), its full
# effect set and enough ray levels for a ray to go through the sphere and reach the floor or mirror.
FIG6_REFRACTION = ("(g) + refraction: the sphere in glass", None, 5)
GLASS = Material(ior=1.5, kd=(0.0, 0.0, 0.0), ka=(0.0, 0.0, 0.0), ks=(0.7, 0.7, 0.7), shininess=200.0)
TREE_DEPTHS = (2, 4, 8)  # the ray levels at which refraction's cost is shown: the tree grows with them


def glass_sphere(scene):
    """The scene with its object named "sphere" (scenes/seed.toml's) made of clear glass."""
    objects = [replace(o, material="glass") if o.name == "sphere" else o for o in scene.objects]
    return replace(scene, materials={**scene.materials, "glass": GLASS}, objects=objects)


def warm_time(scene, geometry, repeat, **kw) -> tuple[float, dict]:
    """Median wall time of a warm render (kernel variant compiled, BVH built once)."""
    renderer = warprt.Renderer(scene, geometry=geometry, **kw)
    result = renderer.render()  # compiles or loads the variant
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        result = renderer.render()
        times.append(time.perf_counter() - t)
    return statistics.median(times), result.stats.rays


def scene_paths() -> list[Path]:
    return sorted((ROOT.parent / "scenes").glob("*.toml")) or [None]


def run(width: int, height: int, repeat: int) -> str:
    lines = [
        "# What each effect costs",
        "",
        f"Warm render time (median of {repeat}) at {width}x{height}, 1 spp, on {platform.machine()} with {os.cpu_count()} cores "
        "(all used). Ratio = time / time of the full render.",
        "Regenerate: `python -m benchmarks.effects`.",
        "",
    ]
    for path in scene_paths():
        scene = warprt.load_scene(path).with_camera(width=width, height=height)
        name = path.stem if path else "default"
        geometry = Geometry(scene)
        full_fx = resolve_effects(scene)
        full_t, full_rays = warm_time(scene, geometry, repeat)
        lines += [f"## {name}", "", f"Full effect set `{full_fx}`: {full_t * 1000:.1f} ms, {full_rays['total']:,} rays.", "",
                  "| render | effects | rays | time (ms) | ratio to full |", "|---|---|---:|---:|---:|"]
        lines.append(f"| full | {full_fx} | {full_rays['total']:,} | {full_t * 1000:.1f} | 1.00 |")
        for effect in full_fx.names:
            t, rays = warm_time(scene, geometry, repeat, disable=[effect])
            lines.append(f"| without {effect} | {resolve_effects(scene, disable=[effect])} | {rays['total']:,} | {t * 1000:.1f} | {t / full_t:.2f} |")
        for label, effects, depth in FIG6:
            s = scene.with_render(max_depth=depth)
            t, rays = warm_time(s, geometry, repeat, effects=effects)
            lines.append(f"| Figure 6 {label} | {resolve_effects(s, allow=effects)} | {rays['total']:,} | {t * 1000:.1f} | {t / full_t:.2f} |")
        if name == "seed":
            label, effects, depth = FIG6_REFRACTION
            s = glass_sphere(scene).with_render(max_depth=depth)
            t, rays = warm_time(s, Geometry(s), repeat, effects=effects)
            lines.append(f"| Figure 6 {label} | {resolve_effects(s, allow=effects)} | {rays['total']:,} | {t * 1000:.1f} | {t / full_t:.2f} |")
        if full_fx.refraction:
            # The ray tree doubles at every dielectric hit: what refraction costs grows with the ray levels.
            for depth in TREE_DEPTHS:
                s = scene.with_render(max_depth=depth)
                t, rays = warm_time(s, geometry, repeat)
                t_off, _ = warm_time(s, geometry, repeat, disable=["refraction"])
                lines.append(f"| max_depth {depth} | {resolve_effects(s)} | {rays['total']:,} ({rays['refraction']:,} refracted) "
                             f"| {t * 1000:.1f} | {t / full_t:.2f} ({t / t_off:.2f} x without refraction) |")
        lines.append("")
    return "\n".join(lines)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--width", type=int, default=512)
    ap.add_argument("--height", type=int, default=384)
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("-o", "--output", default=str(ROOT / "results" / "effects.md"))
    args = ap.parse_args()
    report = run(args.width, args.height, args.repeat)
    out = Path(args.output)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(report + "\n")
    print(report)


if __name__ == "__main__":
    main()
