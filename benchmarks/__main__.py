"""The performance report: every benchmark in one run, written to benchmarks/REPORT.md with its plots.

    python -m benchmarks            # the full report (26 minutes on 2 cores, quiet)
    python -m benchmarks --quick    # small sizes, to check that everything runs
    python -m benchmarks --only accuracy_cost   # one section run again, replaced in the report, the header saying so
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent
RESULTS = ROOT / "results"


def machine() -> str:
    cpu = "unknown CPU"
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    mem = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES") / 2**30
    import drjit
    import mitsuba
    import warp

    return (f"{cpu}, {os.cpu_count()} cores, {mem:.0f} GiB, {platform.system()} {platform.release()}, Python "
            f"{platform.python_version()}, warp-lang {warp.__version__}, Mitsuba {mitsuba.__version__}, Dr.Jit {drjit.__version__}")


def targets(h2h: dict, cast: dict, floor: dict | None = None, orbit: dict | None = None,
            many: dict | None = None, cold: dict | None = None, mirrors: dict | None = None,
            kernel_floor: dict | None = None, gradient: dict | None = None, soft_shadows: dict | None = None) -> str:
    """The performance targets, each measured against Mitsuba or against warprt itself in this run (many
    frames: against a loop, Ray against local): met or not, with the gap."""
    rows_h = h2h["rows"]
    warm = [r["warprt_warm"] / r["mitsuba_llvm_warm"] for r in rows_h]
    hybrid = [r["hybrid_warm"] / r["mitsuba_llvm_warm"] for r in rows_h]
    before = [r["hybrid_warm"] / r["before_warm"] for r in rows_h]
    worst = max(rows_h, key=lambda r: r["hybrid_warm"] / r["before_warm"])["scene"]
    closest = [r["warp_closest_1t"] / r["mitsuba_closest_1t"] for r in cast["rows"]]
    anyhit = [r["warp_any_1t"] / r["mitsuba_any_1t"] for r in cast["rows"]]
    met = lambda ok: "met" if ok else "not met"
    size = f"{rows_h[0]['width']}x{rows_h[0]['height']}"
    rows = [
        (f"Warm {size} frame, every scene: <= 0.6x today's (warprt before the shadow grid and the mirrors' virtual "
         "cameras, every shadow and reflection ray traced)",
         f"{min(before):.2f}x to {max(before):.2f}x (worst: {worst}); against Mitsuba {min(hybrid):.2f}x to {max(hybrid):.2f}x",
         met(max(before) <= 0.6)),
    ]
    if floor:
        mitsuba = {r["scene"]: r["mitsuba_llvm_warm"] for r in rows_h}
        # Only where the replayed frame is warprt's image (the replay has no glass, textures or file normals).
        f = [(r["floor"] / mitsuba[r["scene"]], r["scene"]) for r in floor["rows"]
             if r["scene"] in mitsuba and r.get("identical", True)]
        if f:
            rows.append(("The floor: the warm frame with every shadow and reflection answer free (what the queries left cost)",
                         f"{min(f)[0]:.2f}x to {max(f)[0]:.2f}x Mitsuba on the {len(f)} scenes the replay renders exactly; "
                         f"the frame is {min(hybrid):.2f}x to {max(hybrid):.2f}x", "measured"))
    if kernel_floor:
        from . import kernel_floor as kernel_floor_bench

        rows.append(kernel_floor_bench.target_row(kernel_floor))
    if orbit:
        ratio = orbit["orbit_per_frame"] / orbit["static_warm"]
        rows.append((f"A {orbit['frames']}-frame camera orbit around a {orbit['triangles']:,}-triangle scene: per-frame time "
                     "<= 1.3x the static warm frame",
                     f"{orbit['orbit_per_frame']:.3f} s against {orbit['static_warm']:.3f} s: {ratio:.2f}x "
                     f"({sum(b == 'built' for b in orbit['bvh'])} BVH build)", met(ratio <= 1.3)))
    if cold is not None:
        from . import cold as cold_bench

        rows += cold_bench.target_rows(cold)
    if mirrors is not None:
        from . import mirrors as mirrors_bench

        rows += mirrors_bench.target_rows(mirrors)
    # Issue 23's warm targets: opaque scenes against Mitsuba with the same integrator, glass against the
    # reference's ray tree on Mitsuba (both branches of every split, as warprt).
    for glass, target, ok in ((False, "every opaque scene: <= 2.5x Mitsuba `llvm_ad_rgb` (the goal beyond: 2.0x)",
                               lambda x: x <= 2.5),
                              (True, "every glass scene: < 1.0x Mitsuba running the same ray tree", lambda x: x < 1.0)):
        worst_first = sorted(((r["hybrid_warm"] / r["mitsuba_llvm_warm"], r["scene"]) for r in rows_h
                              if r.get("glass", False) == glass), reverse=True)
        if worst_first:
            rows.append((f"Warm {size} frame, {target}", ", ".join(f"{name} {x:.2f}" for x, name in worst_first),
                         met(ok(worst_first[0][0]))))
    rows += [
        (f"Warm {size} frame, every scene: <= 1.0x Mitsuba `llvm_ad_rgb` (the first round's target)",
         f"{min(hybrid):.2f}x to {max(hybrid):.2f}x (every ray traced: {min(warm):.2f}x to {max(warm):.2f}x)", met(max(hybrid) <= 1.0)),
        ("Rays per second per core: >= 50% of Mitsuba/Embree's on the same mesh",
         f"closest hit {min(closest):.0%} to {max(closest):.0%}, any hit {min(anyhit):.0%} to {max(anyhit):.0%} "
         f"({cast['rows'][0]['triangles']:,} to {cast['rows'][-1]['triangles']:,} triangles, one thread each)",
         met(min(min(closest), min(anyhit)) >= 0.5)),
    ]
    if many is not None:
        from . import batch

        rows += batch.targets(many, met)
    if gradient is not None:
        from . import gradient_cost

        rows += gradient_cost.target_rows(gradient)
    if soft_shadows is not None:
        from . import equal_error

        rows += equal_error.target_rows(soft_shadows)
    lines = ["## Targets", "", "Measured in this run; why the unmet ones are not met is in the last section "
             "(\"What was tried\").", "", "| target | measured | |", "|---|---|---|"]
    lines += [f"| {a} | {b} | {c} |" for a, b, c in rows]
    return "\n".join(lines) + "\n"


# The sections --only runs again: a module with run(quick) and report(data), and with target_rows(data), its
# rows of the Targets table.
SECTIONS = ("accuracy_cost", "growth", "gradient_cost", "equal_error")


def commit() -> str:
    return subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True, cwd=ROOT).stdout.strip()


def replace_section(report: str, section: str, name: str, note: str, tag: str | None = None) -> str:
    """``report`` with the section that starts with ``section``'s first line (a '## ' heading) replaced by
    ``section``, up to the next '## ' heading, and ``note`` (one line saying when it was run) in the header
    in place of an earlier one (a line holding ``tag``, by default the --only command of ``name``)."""
    heading = section.splitlines()[0]
    start = report.find(heading + "\n")
    if not heading.startswith("## ") or start < 0:
        raise SystemExit(f"benchmarks --only {name}: no section '{heading}' in the report to replace")
    end = report.find("\n## ", start + len(heading))
    report = report[:start] + section.rstrip("\n") + "\n\n" + (report[end + 1:] if end >= 0 else "")
    lines = report.splitlines()
    tag = tag or f"`python -m benchmarks --only {name}`"
    lines = [line for line in lines if tag not in line]
    at = next(i for i, line in enumerate(lines) if line.startswith("Generated by")) + 1
    lines.insert(at, note)
    return "\n".join(lines) + "\n"


def replace_target_rows(report: str, rows) -> str:
    """``report`` with the Targets table's rows for ``rows`` ((target, measured, verdict)) replaced where a row
    starts with the same target up to its first comma or colon, else added at the table's end."""
    lines = report.splitlines()
    start = lines.index("## Targets")
    end = max(i for i, line in enumerate(lines[:next((j for j in range(start + 1, len(lines))
                                                      if lines[j].startswith("## ")), len(lines))]) if line.startswith("| "))
    for a, b, c in rows:
        key = "| " + a.split(":")[0].split(",")[0]
        row = f"| {a} | {b} | {c} |"
        at = next((i for i in range(start, end + 1) if lines[i].startswith(key)), None)
        if at is None:
            end += 1
            lines.insert(end, row)
        else:
            lines[at] = row
    return "\n".join(lines) + "\n"


def add_section(report: str, section: str, name: str, note: str) -> str:
    """``report`` with ``section`` added before its "What was tried" part (the end if it has none), and
    ``note`` in the header (replace_section's)."""
    at = report.find("\n## What was tried")
    at = len(report) if at < 0 else at + 1
    report = report[:at] + section.rstrip("\n") + "\n\n" + report[at:]
    heading = section.splitlines()[0]
    return replace_section(report, section, name, note) if heading in report else report


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true", help="small sizes and one repeat: a smoke run, not a report")
    ap.add_argument("--only", choices=SECTIONS, help="run this section alone and replace it in the existing report")
    ap.add_argument("-o", "--output", default=str(ROOT / "REPORT.md"))
    args = ap.parse_args()
    os.environ.setdefault("DRJIT_LIBLLVM_PATH", "/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1")
    RESULTS.mkdir(parents=True, exist_ok=True)
    started = time.time()
    sections = []
    if args.only:
        import importlib

        module = importlib.import_module(f".{args.only}", __package__)
        data = module.run(quick=args.quick)
        (RESULTS / f"{args.only}.json").write_text(json.dumps(data, indent=1, default=str))
        section = module.report(data)
        title = section.splitlines()[0].lstrip("# ")
        note = (f"Section \"{title}\" run again alone by `python -m benchmarks --only {args.only}` at commit "
                f"{commit() or 'unknown'} in {(time.time() - started) / 60:.1f} minutes"
                + (" (--quick: not for quoting)" if args.quick else "") + ".")
        out = Path(args.output)
        text = out.read_text()
        if hasattr(module, "target_rows"):
            text = replace_target_rows(text, module.target_rows(data))
        out.write_text(replace_section(text, section, args.only, note) if section.splitlines()[0] in text.splitlines()
                       else add_section(text, section, args.only, note))
        print(f"replaced '{title}' in {out}", file=sys.stderr)
        return

    from . import cold as cold_bench, effects, head_to_head, raycast, shadow_rays

    q = args.quick
    print("cold start ...", file=sys.stderr, flush=True)
    cold = cold_bench.run(repeat=1 if q else 7)
    (RESULTS / "cold.json").write_text(json.dumps(cold, indent=1))
    sections.append(cold_bench.report(cold))
    print("head to head ...", file=sys.stderr, flush=True)
    h2h = head_to_head.run(*((256, 192) if q else (1024, 768)), repeat=1 if q else 3)
    (RESULTS / "head_to_head.json").write_text(json.dumps(h2h, indent=1))
    sections.append(head_to_head.report(h2h))

    print("ray casting ...", file=sys.stderr, flush=True)
    cast = raycast.run(5 if q else 8, 1 if q else 5)
    (RESULTS / "raycast.json").write_text(json.dumps(cast, indent=1))
    sections.append(raycast.report(cast).replace("# Raw ray casting", "## Raw ray casting", 1))

    from . import floor as floor_bench, orbit as orbit_bench

    print("floor ...", file=sys.stderr, flush=True)
    floor = floor_bench.run(*((256, 192) if q else (1024, 768)), repeat=1 if q else 3)
    (RESULTS / "floor.json").write_text(json.dumps(floor, indent=1))
    sections.append(floor_bench.report(floor))
    from . import kernel_floor as kernel_floor_bench

    print("kernel floor ...", file=sys.stderr, flush=True)
    kfloor = kernel_floor_bench.run(*((128, 96) if q else (1024, 768)), repeat=1 if q else 5,
                                    log=lambda line: print(line, file=sys.stderr, flush=True))
    (RESULTS / "kernel_floor.json").write_text(json.dumps(kfloor, indent=1))
    sections.append(kernel_floor_bench.report(kfloor))
    print("orbit ...", file=sys.stderr, flush=True)
    orbit = orbit_bench.run(*((128, 96, 6, 4) if q else (1024, 768, 20, 7)))
    (RESULTS / "orbit.json").write_text(json.dumps(orbit, indent=1))
    sections.append(orbit_bench.report(orbit))

    from . import mirrors as mirrors_bench

    print("mirrors ...", file=sys.stderr, flush=True)
    mirrors = mirrors_bench.run(*((320, 240) if q else (1024, 768)), repeat=1 if q else 7)
    (RESULTS / "mirrors.json").write_text(json.dumps(mirrors, indent=1))
    sections.append(mirrors_bench.report(mirrors))

    from . import accuracy_cost, equal_error, gradient_cost, growth

    for name, module in (("growth", growth), ("accuracy_cost", accuracy_cost), ("gradient_cost", gradient_cost),
                         ("equal_error", equal_error)):
        print(f"{name} ...", file=sys.stderr, flush=True)
        data = module.run(quick=q)
        (RESULTS / f"{name}.json").write_text(json.dumps(data, indent=1, default=str))
        sections.append(module.report(data))

    print("shadow rays ...", file=sys.stderr, flush=True)
    data = shadow_rays.run(*((256, 192) if q else (1024, 768)), repeat=1 if q else 5)
    (RESULTS / "shadow_rays.json").write_text(json.dumps(data, indent=1))
    sections.append(shadow_rays.report(data))

    print("effects ...", file=sys.stderr, flush=True)
    text = effects.run(*((128, 96) if q else (512, 384)), 1 if q else 5)
    (RESULTS / "effects.md").write_text(text + "\n")
    sections.append(text.replace("# What each effect costs", "## What each effect costs", 1).replace("\n## ", "\n### "))

    from . import batch

    print("many frames ...", file=sys.stderr, flush=True)
    many = batch.run(quick=q, log=lambda line: print(line, file=sys.stderr, flush=True))
    (RESULTS / "batch.json").write_text(json.dumps(many, indent=1))
    sections.append(batch.report(many))
    gradient = json.loads((RESULTS / "gradient_cost.json").read_text())
    soft = json.loads((RESULTS / "equal_error.json").read_text())
    sections.insert(0, targets(h2h, cast, floor, orbit, many, cold, mirrors, kernel_floor=kfloor, gradient=gradient,
                               soft_shadows=soft))

    attempts = (ROOT / "ATTEMPTS.md").read_text() if (ROOT / "ATTEMPTS.md").exists() else ""
    head = commit()
    header = [
        "# warprt performance report",
        "",
        f"Machine: {machine()}.",
        f"Generated by `python -m benchmarks` at commit {head or 'unknown'} in {(time.time() - started) / 60:.1f} minutes"
        + (" (--quick: small sizes, one repeat; not for quoting)" if q else "") + ".",
        "All ratios compare engines measured in this one run, on this machine.",
        "",
    ]
    report = "\n".join(header) + "\n\n".join(s for s in sections if s) + "\n\n" + attempts
    Path(args.output).write_text(report)
    print(f"wrote {args.output}", file=sys.stderr)


if __name__ == "__main__":
    main()
