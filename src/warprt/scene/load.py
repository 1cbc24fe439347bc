"""load_scene: a TOML scene file, a bare mesh file (framed automatically) or the built-in default
scene, with dotted overrides ("camera.width", "lights[0].color") applied before validation;
load_dict, the scene file's schema as a Python dict; and with_overrides, the same scene for other
overrides, from one already loaded."""

from __future__ import annotations

from dataclasses import asdict, fields, replace
from pathlib import Path

from ..diagnostics import collecting
from ..errors import ArgumentError, SceneError, show
from ..timing import timed
from .autoframe import scene_for_mesh
from .meshio import FORMATS, is_mesh_path
from .model import Camera, RenderSettings, Scene
from .reader import read_camera, read_render, scene_from_dict
from .toml_fields import plain, read_toml
from .validate import CheckedContent, validate_scene, validate_view

# The fields with_overrides sets on a loaded scene without reading its file again.
_IN_PLACE = {"camera": {f.name for f in fields(Camera)}, "render": {f.name for f in fields(RenderSettings)}}


def load_scene(path=None, overrides: dict | None = None, up: str | None = None, camera=None) -> Scene:
    """Read a scene: a TOML scene file, any mesh file trimesh reads (seen from its first camera, else
    framed automatically for the overridden camera and image size; only camera.* and render.* can be
    overridden; ``up``: the file's up axis; ``camera``: one of the file's cameras by name or index, or
    "auto" for the framing), or None for the built-in default scene."""
    times: dict = {}
    with timed(times, "load"), collecting(str(path) if path is not None else "default scene"):
        scene = _load_scene(path, overrides, up, camera)
    scene.files = (Path(path if path is not None else default_scene_path()), *scene.files)
    scene.load_seconds = times["load"]
    return scene


def load_dict(d: dict, base=None, source: str = "<dict>") -> Scene:
    """A validated Scene from the scene file's schema as a dict, what tomllib gives for a scene file (as
    Mitsuba's mi.load_dict takes its own): the file's checks and errors, naming ``source`` and the dotted
    field; file names in it (meshes, textures, camera.from) relative to ``base``, else the working folder.
    Tuples, NumPy arrays and numbers, and Paths are read as the lists, numbers and strings a file holds.
    Its warnings are Python warnings (SceneWarning), to filter or catch, as a Scene built in Python has them."""
    if not isinstance(d, dict):
        raise SceneError(source, None, f"expected a dict of the scene file's tables, got {show(d)}")
    times: dict = {}
    with timed(times, "load"):
        scene = scene_from_dict(plain(d), source, base)
    scene.load_seconds = times["load"]
    return scene


def input_kind(path) -> str:
    """What load_scene reads ``path`` as, by its extension: "toml" (a scene file), "mitsuba" (a Mitsuba
    scene file) or "mesh" (a mesh file, framed)."""
    return {".toml": "toml", ".xml": "mitsuba"}.get(Path(path).suffix.lower(), "mesh")


def default_scene_path() -> Path:
    return Path(__file__).parent.parent / "data" / "default.toml"


def apply_overrides(data: dict, overrides: dict, source: str) -> dict:
    """Set dotted keys ("camera.width", "lights[0].color") on a parsed document before validation."""
    for key, value in overrides.items():
        node, parts = data, key.split(".")
        for j, part in enumerate(parts):
            name, index = part, None
            if part.endswith("]") and "[" in part:
                name, idx = part[:-1].split("[", 1)
                if not idx.isdigit():
                    raise SceneError(source, key, "expected an index like lights[0]")
                index = int(idx)
            last = j == len(parts) - 1
            if index is None:
                if last:
                    node[name] = value
                else:
                    node = node.setdefault(name, {})
                    if not isinstance(node, dict):
                        raise SceneError(source, key, f"'{name}' is not a table")
            else:
                arr = node.get(name)
                if not isinstance(arr, list) or index >= len(arr):
                    raise SceneError(source, key, f"there is no {name}[{index}]")
                if last:
                    arr[index] = value
                else:
                    node = arr[index]
    return data


def with_overrides(base: Scene, path, overrides: dict, base_overrides: dict | None = None,
                   content: CheckedContent | None = None) -> Scene:
    """load_scene(path, overrides), made from ``base`` = load_scene(path, base_overrides) without reading
    the file again where the two differ only in camera.* and render.* fields (sets_in_place): those go through the
    reader's own read_camera and read_render on the merged tables (its coercion and checks, the same
    SceneError), then the whole scene's checks, or with ``content`` (validate_scene(base)'s return value)
    only those that depend on the camera and render settings (validate_view: the same SceneError); lights,
    materials and objects are base's own, so a renderer's geometry cache keeps them. Any other difference
    loads the file."""
    times: dict = {}
    with timed(times, "load"):
        base_overrides = base_overrides or {}
        changed = {k: v for k, v in overrides.items() if k not in base_overrides or base_overrides[k] != v}
        in_place = all(k in overrides for k in base_overrides) and all(sets_in_place(k, path) for k in changed)
        if not in_place:
            return load_scene(path, overrides)
        scene = _set_camera_render(base, changed, base.source) if changed else replace(base)
        if content is None:
            validate_scene(scene)
        else:
            validate_view(scene, content)
    scene.load_seconds = times["load"]
    return scene


def sets_in_place(key: str, path=None) -> bool:
    """Whether with_overrides sets the dotted field ``key`` on a scene loaded from ``path``: camera.* and
    render.* of a scene file; of a bare mesh only render.*, as its framing follows its camera."""
    section, _, name = key.partition(".")
    if path is not None and input_kind(path) == "mesh" and section == "camera":
        return False
    return section in _IN_PLACE and name.isidentifier()  # unknown names too: the reader reports them


def _set_camera_render(scene: Scene, overrides: dict, source: str) -> Scene:
    """``scene`` with dotted camera.* and render.* overrides set on its own tables, read again by the reader."""
    doc = {"camera": asdict(scene.camera), "render": {k: v for k, v in asdict(scene.render).items() if v is not None}}
    doc = apply_overrides(doc, overrides, source)
    doc = {section: {k: list(v) if isinstance(v, tuple) else v for k, v in table.items()} for section, table in doc.items()}
    return replace(scene, camera=read_camera(source, doc["camera"]), render=read_render(source, doc["render"]))


def _load_scene(path, overrides, up, camera=None) -> Scene:
    if path is None:
        path = default_scene_path()
    path = Path(path)
    source = str(path)
    kind = input_kind(path)
    if kind == "mitsuba":
        return _load_mitsuba_scene(path, overrides, up)
    if kind == "mesh":
        return _load_mesh_scene(path, overrides, up, camera)
    if camera is not None:
        raise ArgumentError("load_scene", "camera", "applies to a mesh file; in a scene file, write "
                                                    "camera = { from = \"model.glb\", name = \"Camera\" }")
    if up is not None:
        raise ArgumentError("load_scene", "up", "applies to a mesh file; in a scene file, give the object "
                                                "up = \"z\" (or x, y, -x, -y, -z)")
    data = read_toml(path, "scene file")
    if overrides:
        data = apply_overrides(data, overrides, source)
    return scene_from_dict(data, source, path.parent)


def _load_mitsuba_scene(path: Path, overrides, up) -> Scene:
    """A Mitsuba scene file through Mitsuba's parser, then camera.* and render.* overrides as a scene file's."""
    from .mitsuba_xml import read_mitsuba_xml  # imports Mitsuba only when such a file is read

    source = str(path)
    if up is not None:
        raise ArgumentError("load_scene", "up", "applies to a mesh file; a Mitsuba scene places its shapes itself")
    for k in overrides or {}:
        if k.split(".")[0] not in ("camera", "render"):
            raise SceneError(source, k, "only camera.* and render.* can be set for a Mitsuba scene file")
    scene = read_mitsuba_xml(path)
    if overrides:
        scene = _set_camera_render(scene, overrides, source)
    validate_scene(scene)
    return scene


def _load_mesh_scene(path: Path, overrides, up, view=None) -> Scene:
    """A bare mesh: the overrides through the file reader's checks, then the mesh framed for them."""
    source = str(path)
    if path.is_dir():
        raise SceneError(source, None, "is a folder; expected a scene file (.toml) or a mesh file")
    if not is_mesh_path(path):
        raise SceneError(source, None, f"unknown file type '{path.suffix or '(none)'}'; expected a scene file "
                                       f"(.toml) or a mesh file ({', '.join(FORMATS)})")
    doc = {"camera": {}, "render": {}}
    for k in overrides or {}:
        if k.split(".")[0] not in ("camera", "render"):
            raise SceneError(source, k, "only camera.* and render.* can be set for a mesh file")
    if overrides:
        doc = apply_overrides(doc, overrides, source)
    if doc["camera"]:
        read_camera(source, {**asdict(Camera()), **{k: v for k, v in doc["camera"].items() if k not in ("eye", "center", "up")}})
    scene = scene_for_mesh(path, doc["camera"], up, view)
    if doc["render"]:
        base = {k: list(v) if isinstance(v, tuple) else v for k, v in asdict(scene.render).items() if v is not None}
        scene.render = read_render(source, {**base, **doc["render"]})
    # As a scene file is: everything render() relies on is checked here, while the load's warnings
    # are still held (a mesh too far out to frame is then one error, not a warning and an error).
    try:
        validate_scene(scene)
    except SceneError as e:
        framed = e.field is not None and e.field.split("[")[0] in ("lights", "camera.eye", "camera.center", "camera.near")
        if not framed or any(k.split("[")[0] == e.field.split("[")[0] for k in overrides or ()):
            raise
        # The file's own camera and lights (named, where the framing's are not) are the file's to answer for.
        if (e.field.startswith("camera") and scene.cameras and view != "auto") or \
                (e.field.startswith("lights") and any(light.name for light in scene.lights)):
            raise
        # The file did not name that field: the framing made it, from a mesh too large or too far out.
        lo, hi = scene.bounds()
        raise SceneError(source, None, f"cannot frame the mesh, which spans {lo.tolist()} .. {hi.tolist()}: "
                                       f"the framing's {e.field} {e.message}") from None
    return scene
