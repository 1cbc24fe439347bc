"""The behaviour-neutral check: sha256 of the float32 image of every scene on every render path.

    python -m benchmarks.image_hashes > benchmarks/image_hashes.txt     # the list at a commit
    python -m benchmarks.image_hashes --check benchmarks/image_hashes.txt

A refactor that keeps every image bit-identical leaves the list unchanged. Each scene in scenes/
(TOML and Mitsuba XML) at 320x240 and the built-in default scene at 640x480, at 1 and 4 samples per pixel, on the traced
path (every ray from the BVH), the hybrid and grid and mirror shortcuts, the auto policy, with AOVs
and the truncated weights asked for, and the Z-buffer algorithm. Ray counts are hashed with them.
"""

from __future__ import annotations

import argparse
import hashlib
import sys
from pathlib import Path

import numpy as np

import warprt

SCENES = Path(__file__).resolve().parent.parent / "scenes"

PATHS = {
    "traced": dict(primary_query="raytrace", shadow_query="bvh", reflection_query="bvh"),
    "hybrid": dict(primary_query="zbuffer", shadow_query="bvh", reflection_query="bvh"),
    "grid": dict(primary_query="raytrace", shadow_query="grid", reflection_query="bvh"),
    "mirrors": dict(primary_query="raytrace", shadow_query="bvh", reflection_query="mirrors"),
    "shortcuts": dict(primary_query="zbuffer", shadow_query="grid", reflection_query="mirrors"),
    "auto": dict(),
    "aovs": dict(aovs=("depth", "normal", "face")),
    "truncated": dict(report_truncated=True),
    "zbuffer": dict(algorithm="zbuffer"),
}


def cases():
    files = [None] + sorted([*SCENES.glob("*.toml"), *SCENES.glob("*.xml")], key=lambda p: p.stem)
    for path in files:
        size = (640, 480) if path is None else (320, 240)
        for spp in (1, 4):
            yield path, size, spp


def digest(result) -> str:
    h = hashlib.sha256(np.ascontiguousarray(result.image, dtype=np.float32).tobytes())
    rays = getattr(result.stats, "rays", None) or {}
    h.update(repr(sorted(rays.items())).encode())
    trunc = getattr(result.stats, "truncated", None)
    if trunc is not None:
        h.update(np.ascontiguousarray(trunc, dtype=np.float32).tobytes())
    return h.hexdigest()[:32]


def lines(only=None):
    for path, (w, h), spp in cases():
        name = "default" if path is None else path.stem
        if only and name not in only:
            continue
        scene = warprt.load_scene(path, {"camera.width": w, "camera.height": h, "render.spp": spp})
        for label, kw in PATHS.items():
            try:
                result = warprt.render(scene, **kw)
            except warprt.SceneError as e:  # a path a scene cannot take (Z-buffer with glass): its message
                yield f"{name} {w}x{h} spp{spp} {label} refused: {e}"
                continue
            yield f"{name} {w}x{h} spp{spp} {label} {digest(result)}"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--check", type=Path, help="compare with a committed list; exit 1 on any difference")
    ap.add_argument("--only", nargs="+", metavar="SCENE", help="these scenes alone (stems, or 'default')")
    args = ap.parse_args(argv)
    got = list(lines(set(args.only or ())))
    if args.check is None:
        print("\n".join(got))
        return 0
    want = [w for w in args.check.read_text().splitlines() if not args.only or w.split()[0] in args.only]
    diff = [(a, b) for a, b in zip(want, got) if a != b] + [(a, None) for a in want[len(got):]]
    for a, b in diff:
        print(f"- {a}\n+ {b}")
    print(f"{len(got)} images, {len(diff)} differ")
    return 1 if diff or len(got) != len(want) else 0


if __name__ == "__main__":
    sys.exit(main())
