"""The job file: parsing, checking, and its expansion into frames.

A job is a base scene, a camera sequence (an orbit, a list of cameras or a keyframed path; none means
the scene's own camera) and an optional sweep of scene fields; its frames are the Cartesian product of
the sweep's combinations and the cameras, numbered sweep-major,

    frame k = s * n_cameras + c      (s: sweep combination, c: camera index),

so each sweep combination is one contiguous run of the camera sequence. A frame is defined entirely by
its ``overrides`` (dotted scene fields, as load_scene's overrides name them): it is warprt.render of
warprt.load_scene(scene, overrides).

    scene = "scenes/seed.toml"          # relative to the job file, or absolute
    output = "frames/{frame:04d}.png"   # relative to the output folder; .png, .exr or .npz
    aovs = ["depth", "normal"]          # optional
    [set]                               # optional: fields for every frame
    "camera.width" = 320
    [orbit]                             # the eye rotated about the axis through center along up
    frames = 24                         #   by 360 k / frames degrees (right-handed about up)
    # or [[cameras]] eye/center/up/fovy = ... (each optional; one table per camera)
    # or [path] frames = 48, keyframes = [{frame = 0, eye = [..], center = [..]}, {frame = 47, ...}]
    [sweep]
    "render.spp" = [1, 4]               # output may name it: "f{frame:03d}_spp{render.spp}.png"
"""

from __future__ import annotations

import hashlib
import itertools
import json
import math
import os
import string
from dataclasses import dataclass, field
from pathlib import Path

from ..errors import ArgumentError, SceneError, show
from ..image import aov_paths, check_aovs
from ..scene import TableReader, load_scene, read_toml

JOB_KEYS = ("scene", "output", "aovs", "set", "orbit", "cameras", "path", "sweep")
CAMERA_SEQUENCES = ("orbit", "cameras", "path")
CAMERA_FIELDS = ("eye", "center", "up", "fovy")
VECTOR_FIELDS = ("eye", "center", "up")
OUTPUT_FORMATS = (".png", ".exr", ".npz")
DEFAULT_OUTPUT = "frames/{frame:04d}.png"
PLACEHOLDERS = ("frame", "camera", "sweep")
WARMUP_VARIANTS = 8  # at most this many render.* combinations are compiled before the first frame


@dataclass(frozen=True)
class Frame:
    index: int
    camera_index: int
    sweep_index: int
    camera: dict  # the camera fields the camera sequence sets (eye, center, up, fovy)
    sweep: dict  # swept field -> value
    overrides: dict  # everything: the job's [set], the camera, the sweep (dotted scene fields)
    outputs: dict  # "color" -> the image file, and each AOV written beside a PNG -> its file (relative)
    label: str  # how errors name the frame: "frame 5 (cameras[1], render.spp=4)"
    key: str = ""  # fingerprint for --resume: the scene file's bytes, overrides, outputs, aovs


@dataclass
class Job:
    path: Path
    source: str  # how errors name the job file
    scene_path: Path
    output_dir: Path
    output: str
    aovs: tuple
    base_overrides: dict
    sequence: str  # "orbit", "cameras", "path" or "scene"
    n_cameras: int
    sweep: dict
    frames: list = field(default_factory=list)
    cameras: list = field(default_factory=list)  # per camera: its fields (an orbit's are filled in by check_scene)
    camera_labels: list = field(default_factory=list)
    device: str = "cpu"  # the Warp device the workers render on (batch()'s device)

    def spec(self) -> dict:
        """What a worker needs to hold the scene (picklable, small). ``warmup``: the overrides of one frame
        for each distinct set of render.* values (the first few), whose kernel variants a worker loads
        before its first frame. Made from the job file alone (the first camera as the file gives it, an
        orbit's none: its eyes change no kernel), so workers can start before check_scene()."""
        first = self.cameras[0] if self.sequence in ("cameras", "path") else {}
        warmup, seen = [], set()
        for combo in itertools.product(*self.sweep.values()):
            overrides = {**self.base_overrides, **{f"camera.{f}": v for f, v in first.items()}, **dict(zip(self.sweep, combo))}
            settings = json.dumps({k: v for k, v in overrides.items() if k.startswith("render.")}, sort_keys=True)
            if settings not in seen:
                seen.add(settings)
                warmup.append(overrides)
                if len(warmup) == WARMUP_VARIANTS:
                    break
        return {"scene": str(self.scene_path), "aovs": list(self.aovs), "output_dir": str(self.output_dir),
                "warmup": warmup, "device": self.device}

    def frame_count(self, shard: tuple[int, int] | None = None) -> int:
        """How many frames the job (or its shard) has, known before check_scene() expands an orbit."""
        n = self.n_cameras * math.prod(len(v) for v in self.sweep.values())
        return n if shard is None else len(range(shard[0], n, shard[1]))


def _flatten(source, table: dict, prefix: str, what: str) -> dict:
    """[sweep] render.spp = [..] parses as nested tables, "render.spp" = [..] as a dotted key: both are
    the field render.spp."""
    out = {}
    for k, v in table.items():
        name = f"{prefix}.{k}" if prefix else k
        if isinstance(v, dict):
            if not v:
                raise SceneError(source, f"{what}.{name}", "expected a value, got an empty table")
            out.update(_flatten(source, v, name, what))
        else:
            out[name] = v
    return out


def _camera_table(source, where, t: dict) -> dict:
    if not isinstance(t, dict):
        raise SceneError(source, where, f"expected a table, got {show(t)}")
    r = TableReader(source, t, where)
    r.check_keys(CAMERA_FIELDS, what="camera field")
    return {k: list(r.vector(k, whole=True)) if k in VECTOR_FIELDS else r.number(k, whole=True) for k in t}


def orbit_eye(eye, center, up, degrees: float) -> list:
    """``eye`` rotated by ``degrees`` (right-handed) about the axis through ``center`` along ``up``
    (Rodrigues' formula in float64). 0 degrees gives ``eye`` back exactly."""
    if degrees == 0.0:
        return [float(x) for x in eye]
    a = [float(x) for x in up]
    n = math.sqrt(sum(x * x for x in a))
    a = [x / n for x in a]
    v = [float(e) - float(c) for e, c in zip(eye, center)]
    th = math.radians(degrees)
    cos, sin = math.cos(th), math.sin(th)
    cross = [a[1] * v[2] - a[2] * v[1], a[2] * v[0] - a[0] * v[2], a[0] * v[1] - a[1] * v[0]]
    dot = sum(x * y for x, y in zip(a, v))
    return [float(c) + v[i] * cos + cross[i] * sin + a[i] * dot * (1.0 - cos) for i, c in enumerate(center)]


def _lerp(a, b, t):
    if isinstance(a, list):
        return [x + (y - x) * t for x, y in zip(a, b)]
    return a + (b - a) * t


def _path_cameras(source, t: dict) -> list[dict]:
    r = TableReader(source, t, "path")
    r.check_keys(("frames", "keyframes"))
    keys = t.get("keyframes")
    if not isinstance(keys, list) or len(keys) < 2:
        raise SceneError(source, "path.keyframes", f"expected a list of at least 2 keyframe tables, got {show(keys)}")
    frames, cams = [], []
    for i, kf in enumerate(keys):
        where = f"path.keyframes[{i}]"
        if not isinstance(kf, dict):
            raise SceneError(source, where, f"expected a table {{frame = N, eye = [..], ...}}, got {show(kf)}")
        f = TableReader(source, kf, where).integer("frame", lo=0)
        kf = {k: v for k, v in kf.items() if k != "frame"}
        if frames and f <= frames[-1]:
            raise SceneError(source, f"{where}.frame", f"keyframes must be in increasing frame order; {f} follows {frames[-1]}")
        cam = _camera_table(source, where, kf)
        if not cam:
            raise SceneError(source, where, f"a keyframe sets at least one of: {', '.join(CAMERA_FIELDS)}")
        if cams and set(cam) != set(cams[0]):
            raise SceneError(source, where, f"every keyframe must set the same camera fields; keyframes[0] sets "
                                            f"{', '.join(sorted(cams[0]))}, this one {', '.join(sorted(cam))}")
        frames.append(f)
        cams.append(cam)
    if frames[0] != 0:
        raise SceneError(source, "path.keyframes[0].frame", f"the first keyframe must be frame 0, got {frames[0]}")
    n = r.integer("frames", frames[-1] + 1, lo=1)
    if frames[-1] != n - 1:
        raise SceneError(source, "path.frames", f"the last keyframe (frame {frames[-1]}) must be the last frame, {n - 1}")
    out = []
    for k in range(n):
        j = max(i for i, f in enumerate(frames) if f <= k)
        if frames[j] == k:
            out.append({f: (list(v) if isinstance(v, list) else v) for f, v in cams[j].items()})
        else:
            tt = (k - frames[j]) / (frames[j + 1] - frames[j])
            out.append({f: _lerp(cams[j][f], cams[j + 1][f], tt) for f in cams[j]})
    return out


class _FieldFormatter(string.Formatter):
    """str.format with field names taken whole: {render.spp} and {lights[0].color} are keys."""

    def get_field(self, field_name, args, kwargs):
        if field_name not in kwargs:
            raise KeyError(field_name)
        return kwargs[field_name], field_name


def _placeholder_value(v):
    """A swept list in a file name: [1, 0.9, 0.8] -> "1_0.9_0.8"; scalars keep their type, so format
    specs like {render.spp:02d} work."""
    if isinstance(v, list):
        return "_".join(str(_placeholder_value(x)) for x in v)
    return v


def _fingerprint(scene_bytes: bytes, frame_overrides: dict, outputs: dict, aovs) -> str:
    h = hashlib.sha256(scene_bytes)
    h.update(json.dumps({"overrides": frame_overrides, "outputs": outputs, "aovs": list(aovs)}, sort_keys=True).encode())
    return h.hexdigest()[:20]


def load_job(path, output_dir=None) -> Job:
    """Read and check a job file and expand it into frames; a SceneError names the job file and the
    field. Nothing here needs the scene: check_scene() checks it (and completes an orbit's cameras)."""
    path = Path(path)
    source = str(path)
    data = read_toml(path, "job file")
    TableReader(source, data, "").check_keys(JOB_KEYS)

    scene = data.get("scene")
    if not isinstance(scene, str) or not scene:
        raise SceneError(source, "scene", "is required: the scene file, relative to the job file" if scene is None
                         else f"expected a path, got {show(scene)}")
    # Absolute: worker processes, Ray actors and other machines do not share the driver's folder.
    scene_path = (Path(scene) if os.path.isabs(scene) else path.parent / scene).resolve()
    if not scene_path.is_file():
        raise SceneError(source, "scene", f"scene file not found: {scene_path}")

    output = data.get("output", DEFAULT_OUTPUT)
    if not isinstance(output, str) or not output:
        raise SceneError(source, "output", f"expected a path template, got {show(output)}")
    if Path(output).suffix.lower() not in OUTPUT_FORMATS:
        raise SceneError(source, "output", f"unknown image extension '{Path(output).suffix or '(none)'}'; "
                                           f"expected one of: {', '.join(OUTPUT_FORMATS)}")
    aovs = check_aovs(data.get("aovs", []), "aovs", source)

    base = data.get("set", {})
    if not isinstance(base, dict):
        raise SceneError(source, "set", f"expected a table of scene fields, got {show(base)}")
    base = _flatten(source, base, "", "set")

    seqs = [k for k in CAMERA_SEQUENCES if k in data]
    if len(seqs) > 1:
        raise SceneError(source, seqs[1], f"a job has one camera sequence; it already has [{seqs[0]}]")
    sequence = seqs[0] if seqs else "scene"
    if sequence == "orbit":
        t = data["orbit"]
        if not isinstance(t, dict):
            raise SceneError(source, "orbit", f"expected a table [orbit] frames = N, got {show(t)}")
        r = TableReader(source, t, "orbit")
        r.check_keys(("frames",))
        n = r.integer("frames", lo=1)
        cams = [None] * n  # the eyes follow from the scene's camera: check_scene
        labels = [f"orbit {k}/{n}" for k in range(n)]
    elif sequence == "cameras":
        t = data["cameras"]
        if not isinstance(t, list) or not t or not all(isinstance(c, dict) for c in t):
            raise SceneError(source, "cameras", f"expected one or more [[cameras]] tables, got {show(t)}")
        cams = [_camera_table(source, f"cameras[{i}]", c) for i, c in enumerate(t)]
        labels = [f"cameras[{i}]" for i in range(len(cams))]
    elif sequence == "path":
        t = data["path"]
        if not isinstance(t, dict):
            raise SceneError(source, "path", f"expected a table [path] frames = N, keyframes = [...], got {show(t)}")
        cams = _path_cameras(source, t)
        labels = [f"path frame {k}" for k in range(len(cams))]
    else:
        cams, labels = [{}], ["scene camera"]

    sweep = data.get("sweep", {})
    if not isinstance(sweep, dict):
        raise SceneError(source, "sweep", f"expected a table of scene fields and value lists, got {show(sweep)}")
    sweep = _flatten(source, sweep, "", "sweep")
    camera_set = {"camera.eye"} if sequence == "orbit" else {f"camera.{f}" for c in cams for f in c}
    for name, values in sweep.items():
        if not isinstance(values, list) or not values:
            raise SceneError(source, f"sweep.{name}", f"expected a non-empty list of values, got {show(values)}")
        if name in camera_set:
            raise SceneError(source, f"sweep.{name}", f"is set by the job's [{sequence}] already")
        if name in base:
            raise SceneError(source, f"sweep.{name}", "is also in [set]; a field is either set or swept")
        if name in PLACEHOLDERS:
            raise SceneError(source, f"sweep.{name}", f"'{name}' is not a scene field")

    job = Job(path=path, source=source, scene_path=scene_path,
              output_dir=(Path(output_dir) if output_dir is not None else path.parent).resolve(),
              output=output, aovs=aovs, base_overrides=base, sequence=sequence, n_cameras=len(cams), sweep=sweep,
              cameras=cams, camera_labels=labels)
    if sequence != "orbit":
        _expand(job)
    return job


def _expand(job: Job):
    source = job.source
    combos = list(itertools.product(*job.sweep.values())) if job.sweep else [()]
    names = list(job.sweep)
    fmt = _FieldFormatter()
    scene_bytes = job.scene_path.read_bytes()
    frames, seen = [], {}
    for s, combo in enumerate(combos):
        sw = dict(zip(names, combo))
        for c, cam in enumerate(job.cameras):
            k = s * len(job.cameras) + c
            ov = dict(job.base_overrides)
            ov.update({f"camera.{f}": v for f, v in cam.items()})
            ov.update(sw)
            values = {"frame": k, "camera": c, "sweep": s, **{n: _placeholder_value(v) for n, v in sw.items()}}
            try:
                rel = fmt.format(job.output, **values)
            except KeyError as e:
                allowed = list(PLACEHOLDERS) + names
                raise SceneError(source, "output", f"unknown placeholder {{{e.args[0]}}}; expected one of: "
                                                   f"{', '.join('{' + a + '}' for a in allowed)}") from None
            except (ValueError, IndexError, TypeError) as e:
                raise SceneError(source, "output", f"bad template '{job.output}': {e}") from None
            if rel in seen:
                raise SceneError(source, "output", f"frames {seen[rel]} and {k} would both write '{rel}'; "
                                                   "put {frame} (or the swept fields) in the file name")
            seen[rel] = k
            outputs = {"color": rel, **{name: str(p) for name, p in aov_paths(Path(rel), job.aovs).items()}}
            label = ", ".join([job.camera_labels[c]] + [f"{n}={show(v)}" for n, v in sw.items()])
            frames.append(Frame(index=k, camera_index=c, sweep_index=s, camera=cam, sweep=sw, overrides=ov,
                                outputs=outputs, label=f"frame {k} ({label})",
                                key=_fingerprint(scene_bytes, ov, outputs, job.aovs)))
    job.frames = frames


def check_scene(job: Job):
    """Load the base scene (with [set]) and each swept value on its own: a bad scene, [set] field or
    swept value fails here, naming it, before any worker starts. Completes an orbit's cameras (they
    need the scene's eye, center and up). Returns the base Scene."""
    try:
        base = load_scene(job.scene_path, overrides=dict(job.base_overrides))
    except SceneError as e:
        where = f"set.{e.field}" if e.field in job.base_overrides else "scene"
        raise SceneError(job.source, where, " ".join(str(e).split())) from None
    for name, values in job.sweep.items():
        for i, v in enumerate(values):
            try:
                load_scene(job.scene_path, overrides={**job.base_overrides, name: v})
            except SceneError as e:
                raise SceneError(job.source, f"sweep.{name}[{i}]", " ".join(str(e).split())) from None
    if job.sequence == "orbit":
        cam = base.camera
        n = job.n_cameras
        job.cameras = [{"eye": orbit_eye(cam.eye, cam.center, cam.up, 360.0 * k / n)} for k in range(n)]
        _expand(job)
    return base


def select_shard(frames: list, shard: tuple[int, int] | None) -> list:
    """Frames k with k mod N == I."""
    if shard is None:
        return list(frames)
    i, n = shard
    return [f for f in frames if f.index % n == i]


def parse_shard(text: str | None, env=None) -> tuple[int, int] | None:
    """'I/N', or 'auto' / 'auto/N': the index (and count) from the scheduler's environment.

    auto reads, first found: SLURM_ARRAY_TASK_ID with SLURM_ARRAY_TASK_MIN (default 0),
    SLURM_ARRAY_TASK_STEP (default 1) and SLURM_ARRAY_TASK_COUNT (I = (ID - MIN) / STEP, N = COUNT);
    JOB_COMPLETION_INDEX (a Kubernetes Indexed Job; Kubernetes sets no count, so N comes from 'auto/N'
    or WARPRT_SHARD_COUNT); WARPRT_SHARD_INDEX with WARPRT_SHARD_COUNT. An N given in 'auto/N' must
    agree with SLURM's count."""
    if text is None:
        return None
    env = os.environ if env is None else env

    def num(v, what):
        try:
            return int(str(v).strip())
        except ValueError:
            raise ArgumentError("batch", "shard", f"{what} is not an integer: {v!r}") from None

    head, _, tail = text.partition("/")
    n = num(tail, "the shard count") if tail else None
    if head.strip() == "auto":
        if "SLURM_ARRAY_TASK_ID" in env:
            tid = num(env["SLURM_ARRAY_TASK_ID"], "SLURM_ARRAY_TASK_ID")
            lo = num(env.get("SLURM_ARRAY_TASK_MIN", 0), "SLURM_ARRAY_TASK_MIN")
            step = num(env.get("SLURM_ARRAY_TASK_STEP", 1), "SLURM_ARRAY_TASK_STEP")
            if step < 1 or (tid - lo) % step:
                raise ArgumentError("batch", "shard", f"SLURM array task {tid} is not on the array's grid (min {lo}, step {step})")
            i = (tid - lo) // step
            count = env.get("SLURM_ARRAY_TASK_COUNT")
            if count is not None:
                c = num(count, "SLURM_ARRAY_TASK_COUNT")
                if n is not None and n != c:
                    raise ArgumentError("batch", "shard", f"auto/{n} disagrees with SLURM_ARRAY_TASK_COUNT={c}")
                n = c
        elif "JOB_COMPLETION_INDEX" in env:
            i = num(env["JOB_COMPLETION_INDEX"], "JOB_COMPLETION_INDEX")
            if n is None and "WARPRT_SHARD_COUNT" in env:
                n = num(env["WARPRT_SHARD_COUNT"], "WARPRT_SHARD_COUNT")
        elif "WARPRT_SHARD_INDEX" in env:
            i = num(env["WARPRT_SHARD_INDEX"], "WARPRT_SHARD_INDEX")
            if n is None and "WARPRT_SHARD_COUNT" in env:
                n = num(env["WARPRT_SHARD_COUNT"], "WARPRT_SHARD_COUNT")
        else:
            raise ArgumentError("batch", "shard", "auto found no shard index in the environment (SLURM_ARRAY_TASK_ID, "
                                                    "JOB_COMPLETION_INDEX or WARPRT_SHARD_INDEX)")
        if n is None:
            raise ArgumentError("batch", "shard", "auto found a shard index but no count: give it as auto/N "
                                                    "(or set WARPRT_SHARD_COUNT)")
    else:
        if n is None:
            raise ArgumentError("batch", "shard", f"expected I/N (e.g. 0/4) or auto, got {text!r}")
        i = num(head, "the shard index")
    if n < 1 or not 0 <= i < n:
        raise ArgumentError("batch", "shard", f"expected 0 <= I < N, got {i}/{n}")
    return i, n
