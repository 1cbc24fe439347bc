"""glTF 2.0 and GLB, read from the JSON and its buffers (trimesh rounds base colours to 8 bits, keeps
normalized integer attributes raw and ignores KHR_texture_transform).

What is read: the default scene's node tree (matrix or TRS; each node using a mesh is a placed copy,
EXT_mesh_gpu_instancing too), triangle, strip and fan primitives, POSITION, NORMAL, TEXCOORD_n,
COLOR_0 (linear, as the spec says), and per material baseColorFactor times baseColorTexture (embedded,
data URI or file; sRGB) with KHR_texture_transform and the sampler's wrapS/wrapT, and doubleSided
(false, the default, culls back faces); primitives without a material get the specification's default; perspective cameras and KHR_lights_punctual lights placed
by their nodes. glTF is y-up and in metres by its spec.
"""

from __future__ import annotations

import base64
import json
import math
import struct
from dataclasses import replace
from pathlib import Path
from urllib.parse import unquote

import numpy as np

from ...diagnostics import warn
from ...errors import SceneError, one_line, show
from ..dielectric_formats import dielectric_from_gltf
from ..camera import FileCamera, look_from_matrix
from ..model import Light, Material
from ..texture import image_texture
from . import MeshFile, MeshPart, unique_name, unit_rows, weld_corners

_COMPONENT = {5120: np.int8, 5121: np.uint8, 5122: np.int16, 5123: np.uint16, 5125: np.uint32, 5126: np.float32}
_WIDTH = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT2": 4, "MAT3": 9, "MAT4": 16}
_WRAP = {10497: "repeat", 33071: "clamp", 33648: "mirror"}  # the sampler's wrapS / wrapT as Texture.wrap
# What the specification gives a primitive without a material: base colour 1, metallic 1, roughness 1.
# A rough metal has no highlight to speak of, and Phong has no metallic term: kd 1 and no ks.
# Like every glTF material unless it says doubleSided, it is single-sided (three.js: FrontSide).
GLTF_DEFAULT_MATERIAL = Material(kd=(1.0, 1.0, 1.0), ka=(1.0, 1.0, 1.0), ks=(0.0, 0.0, 0.0), double_sided=False)
_UNREAD_MATERIAL_EXTENSIONS = {"KHR_materials_volume": "volume",
                               "KHR_materials_clearcoat": "clearcoat", "KHR_materials_sheen": "sheen"}


def read_gltf(path: Path) -> MeshFile:
    src = str(path)
    try:
        doc = _Document(path)
        return doc.mesh_file()
    except SceneError:
        raise
    except (KeyError, IndexError, TypeError, ValueError, struct.error, OSError) as e:
        raise SceneError(src, None, f"cannot read {path.suffix[1:].upper()} file: {type(e).__name__}: {one_line(e, type(e).__name__)}") from None


class _Document:
    def __init__(self, path: Path):
        self.path, self.src = path, str(path)
        data = path.read_bytes()
        binary = None
        if data[:4] == b"glTF":
            length = struct.unpack("<I", data[8:12])[0]
            offset, doc = 12, None
            while offset + 8 <= min(length, len(data)):
                size, kind = struct.unpack("<I4s", data[offset:offset + 8])
                chunk = data[offset + 8:offset + 8 + size]
                if kind == b"JSON":
                    doc = json.loads(chunk)
                elif kind == b"BIN\0":
                    binary = chunk
                offset += 8 + size
            if doc is None:
                raise SceneError(self.src, None, "the GLB file has no JSON chunk")
        else:
            try:
                doc = json.loads(data.decode("utf-8-sig"))
            except UnicodeDecodeError as e:
                raise SceneError(self.src, None, f"not a glTF file (not UTF-8 JSON text: byte 0x{e.object[e.start]:02x} "
                                                 f"at offset {e.start})") from None
            except json.JSONDecodeError as e:
                raise SceneError(self.src, None, f"not a glTF file (not JSON: {e.msg} at line {e.lineno}, "
                                                 f"column {e.colno})") from None
            except RecursionError:
                raise SceneError(self.src, None, "not a glTF file (JSON nested too deeply to read)") from None
        if not isinstance(doc, dict):
            raise SceneError(self.src, None, "not a glTF file (the JSON is not an object)")
        self.doc = doc
        for ext in doc.get("extensionsRequired", []):
            if ext in ("KHR_draco_mesh_compression", "EXT_meshopt_compression"):
                raise SceneError(self.src, None, f"compressed geometry ({ext}) is not supported; "
                                                 "export the file without compression")
        self.buffers = [binary if "uri" not in b and i == 0 else self._uri(b["uri"])
                        for i, b in enumerate(doc.get("buffers", []))]
        self._accessors = {}
        self._range_warned = False

    def _uri(self, uri: str) -> bytes:
        if uri.startswith("data:"):
            return base64.b64decode(uri.split(",", 1)[1])
        try:
            return (self.path.parent / unquote(uri)).read_bytes()
        except FileNotFoundError:
            raise SceneError(self.src, None, f"buffer file not found: {unquote(uri)}") from None

    def view(self, i: int) -> tuple[bytes, int | None]:
        v = self.doc["bufferViews"][i]
        buf = self.buffers[v["buffer"]]
        start = v.get("byteOffset", 0)
        return buf[start:start + v["byteLength"]], v.get("byteStride")

    def accessor(self, i: int) -> np.ndarray:
        """(count, components): float64 for float and normalized data (integers divided by their
        type's maximum, as the spec says), int64 for indices; byteStride and sparse accessors read."""
        if i in self._accessors:
            return self._accessors[i]
        a = self.doc["accessors"][i]
        dtype = np.dtype(_COMPONENT[a["componentType"]]).newbyteorder("<")
        width, count = _WIDTH[a["type"]], a["count"]
        if "bufferView" in a:
            raw, stride = self.view(a["bufferView"])
            element = dtype.itemsize * width
            stride = stride or element
            start = a.get("byteOffset", 0)
            if count and start + (count - 1) * stride + element > len(raw):
                raise SceneError(self.src, f"accessors[{i}]", "reaches past the end of its buffer")
            rows = np.lib.stride_tricks.as_strided(np.frombuffer(raw, np.uint8, offset=start), (count, element), (stride, 1))
            out = np.ascontiguousarray(rows).view(dtype).reshape(count, width)
        else:
            out = np.zeros((count, width), dtype)
        if "sparse" in a:
            sparse = a["sparse"]
            out = out.copy()
            raw, _ = self.view(sparse["indices"]["bufferView"])
            idx = np.frombuffer(raw, np.dtype(_COMPONENT[sparse["indices"]["componentType"]]).newbyteorder("<"),
                                sparse["count"], sparse["indices"].get("byteOffset", 0))
            raw, _ = self.view(sparse["values"]["bufferView"])
            out[idx] = np.frombuffer(raw, dtype, sparse["count"] * width, sparse["values"].get("byteOffset", 0)).reshape(-1, width)
        if dtype.kind == "f":
            result = out.astype(np.float64)
        elif a.get("normalized"):
            result = out.astype(np.float64) / np.iinfo(dtype).max
            if dtype.kind == "i":
                result = np.maximum(result, -1.0)
        else:
            result = out.astype(np.int64)
        self._accessors[i] = result
        return result

    def texture(self, index: int, where: str):
        """The Texture of textures[index] (sRGB: the only texture read is the base colour), or None."""
        t = self.doc["textures"][index]
        source = t.get("source")
        if source is None and "EXT_texture_webp" in t.get("extensions", {}):
            source = t["extensions"]["EXT_texture_webp"].get("source")
        if source is None:
            formats = ", ".join(t.get("extensions", {})) or "no image"
            warn(self.src, where, f"texture {index} is in a format not read here ({formats}); the material is untextured")
            return None
        sampler = self.doc.get("samplers", [{}])[t["sampler"]] if "sampler" in t else {}
        wrap = []
        for axis in ("wrapS", "wrapT"):
            code = sampler.get(axis, 10497)
            if code not in _WRAP:
                warn(self.src, where, f"sampler {axis} {code} is not a glTF wrap mode; sampled as repeat")
            wrap.append(_WRAP.get(code, "repeat"))
        image = self.doc["images"][source]
        try:
            if "bufferView" in image:
                raw, _ = self.view(image["bufferView"])
                texture = image_texture(bytes(raw), srgb=True, source=f"{self.src}: images[{source}]")
            elif image["uri"].startswith("data:"):
                texture = image_texture(self._uri(image["uri"]), srgb=True, source=f"{self.src}: images[{source}]")
            else:
                texture = image_texture(self.path.parent / unquote(image["uri"]), srgb=True)
        except SceneError as e:
            warn(self.src, where, f"{e}; the material is untextured")
            return None
        # wrapT acts on the glTF v, which runs down the image, ours up: clamp and mirror commute with v -> 1 - v.
        return texture.wrapped(*wrap)

    def emission(self, m: dict, where: str) -> tuple | None:
        """The material's radiance L_e, as Blender's importer reads it: emissiveFactor times
        KHR_materials_emissive_strength's emissiveStrength (1 without it); None where it is black. An
        emissiveTexture is not read (its factor is, with a warning)."""
        factor = m.get("emissiveFactor", [0.0, 0.0, 0.0])
        strength = m.get("extensions", {}).get("KHR_materials_emissive_strength", {}).get("emissiveStrength", 1.0)
        bad = lambda x: isinstance(x, bool) or not isinstance(x, (int, float)) or not math.isfinite(x) or x < 0
        if not isinstance(factor, list) or len(factor) != 3 or any(bad(x) for x in factor):
            raise SceneError(self.src, f"{where}.emissiveFactor", f"expected 3 non-negative numbers, got {show(factor)}")
        if bad(strength):
            raise SceneError(self.src, f"{where}.emissiveStrength", f"expected a non-negative number, got {show(strength)}")
        if "emissiveTexture" in m and max(factor) > 0.0:
            warn(self.src, where, "the emissive texture is not read: the material emits its emissiveFactor everywhere")
        emission = tuple(float(x) * float(strength) for x in factor)
        return emission if max(emission) > 0.0 else None

    def material(self, i: int) -> tuple[Material, int]:
        """materials[i] as Phong (the base colour, times its texture, is kd and ka; metallic-roughness
        has no Phong term here) and the texture coordinate set its texture reads."""
        m = self.doc["materials"][i]
        where = f"materials[{i}] ({m.get('name', '')})" if m.get("name") else f"materials[{i}]"
        pbr = m.get("pbrMetallicRoughness", {})
        factor = pbr.get("baseColorFactor", [1.0, 1.0, 1.0, 1.0])
        info = pbr.get("baseColorTexture")
        spec_gloss = m.get("extensions", {}).get("KHR_materials_pbrSpecularGlossiness")
        if spec_gloss and "pbrMetallicRoughness" not in m:  # the retired extension: its diffuse colour
            factor = spec_gloss.get("diffuseFactor", [1.0, 1.0, 1.0, 1.0])
            info = spec_gloss.get("diffuseTexture")
        kd = tuple(float(x) for x in factor[:3])
        if m.get("alphaMode", "OPAQUE") != "OPAQUE" or (len(factor) > 3 and factor[3] < 1.0):
            warn(self.src, where, "transparency (alphaMode, base colour alpha) is not rendered; the material is opaque")
        emission = self.emission(m, where)
        for ext, what in _UNREAD_MATERIAL_EXTENSIONS.items():
            if ext in m.get("extensions", {}):
                warn(self.src, where, f"{what} ({ext}) is not rendered")
        texture, tex_coord = None, 0
        if info is not None:
            texture = self.texture(info["index"], where)
            uv_map, tex_coord = _texture_transform(info)
            if texture is not None:
                texture = texture.mapped(uv_map)
        double_sided = m.get("doubleSided", False)  # the specification's default: back faces culled
        if not isinstance(double_sided, bool):
            raise SceneError(self.src, f"{where}.doubleSided", f"expected true or false, got {show(double_sided)}")
        material = Material(kd=kd, ka=kd, ks=(0.0, 0.0, 0.0), kd_texture=texture, ka_texture=texture,
                            double_sided=double_sided, emission=emission)
        dielectric = dielectric_from_gltf(m, self.src, where)
        if dielectric:  # KHR_materials_volume: "the doubleSided property has no effect on volume boundaries"
            dielectric["double_sided"] = True
        return replace(material, **dielectric), tex_coord

    def mesh_file(self) -> MeshFile:
        doc = self.doc
        names: list[str] = []
        materials, tex_coords = [], []
        for i, m in enumerate(doc.get("materials", [])):
            phong, tex_coord = self.material(i)
            name = unique_name(m.get("name") or f"material{i}", names)
            names.append(name)
            materials.append((name, phong))
            tex_coords.append(tex_coord)
        scenes = doc.get("scenes")
        roots = scenes[doc.get("scene", 0)].get("nodes", []) if scenes else _roots(doc)
        parts, cameras, lights = [], [], []
        stack = [(n, np.eye(4)) for n in roots]
        while stack:
            ni, parent = stack.pop(0)
            node = doc["nodes"][ni]
            world = parent @ _node_matrix(node)
            stack += [(c, world) for c in node.get("children", [])]
            if "camera" in node:
                cameras.append((ni, node, world))
            punctual = node.get("extensions", {}).get("KHR_lights_punctual")
            if punctual is not None and "light" in punctual:
                lights.append((ni, self._light(node, ni, punctual["light"], world)))
            if "mesh" not in node:
                continue
            label = node.get("name") or f"nodes[{ni}]"
            for k, instance in enumerate(self._instances(node)):
                placement = world @ instance
                for pi, prim in enumerate(doc["meshes"][node["mesh"]]["primitives"]):
                    part = self._primitive(prim, placement, materials, tex_coords,
                                           f"{label}/{pi}" + (f"[{k}]" if k else ""))
                    if part is not None:
                        parts.append(part)
        if any((p.face_material < 0).any() for p in parts):  # the specification's default material
            materials.append((unique_name("default", names), GLTF_DEFAULT_MATERIAL))
            for p in parts:
                p.face_material[p.face_material < 0] = len(materials) - 1
        # In the order of their nodes in the file (the first camera is the first the file lists), not of the tree walk.
        placed = []
        for ni, node, world in sorted(cameras, key=lambda c: c[0]):
            placed.append(self._camera(node, ni, world, [c.name for c in placed]))
        lights = [light for _, light in sorted(lights, key=lambda x: x[0])]
        return MeshFile(self.path, parts, materials, up_axis="Y", cameras=placed, lights=lights)

    def _camera(self, node, ni: int, world: np.ndarray, taken) -> FileCamera:
        """A node's camera: it looks down the node's -z with +y up; yfov is vertical (radians)."""
        ci = node["camera"]
        cam = self.doc["cameras"][ci]
        name = unique_name(node.get("name") or cam.get("name") or f"cameras[{ci}]", taken)
        kind = cam.get("type", "perspective")
        if kind == "perspective":
            p = cam.get("perspective", {})
            if "yfov" not in p:
                raise SceneError(self.src, f"cameras[{ci}].perspective.yfov", "is required")
            yfov, znear = p["yfov"], p.get("znear", 1.0)
            if not (isinstance(yfov, (int, float)) and 0 < yfov < math.pi):
                raise SceneError(self.src, f"cameras[{ci}].perspective.yfov", f"expected radians in (0, pi), got {yfov!r}")
            if not (isinstance(znear, (int, float)) and znear > 0):
                raise SceneError(self.src, f"cameras[{ci}].perspective.znear", f"expected a number > 0, got {znear!r}")
            return look_from_matrix(world, name, kind, math.degrees(yfov), znear, p.get("aspectRatio"))
        return look_from_matrix(world, name, "orthographic", 45.0, 1.0)

    def _light(self, node, ni: int, li: int, world: np.ndarray) -> Light:
        """A KHR_lights_punctual light placed by its node: it shines down the node's -z. Its colour
        times intensity is C_l (candela for point and spot, lux for directional); its falloff the
        physical inverse square."""
        try:
            light = self.doc["extensions"]["KHR_lights_punctual"]["lights"][li]
        except (KeyError, IndexError, TypeError):
            raise SceneError(self.src, f"nodes[{ni}].extensions.KHR_lights_punctual.light",
                             f"there is no light {li} in the file's KHR_lights_punctual lights") from None
        where = f"KHR_lights_punctual.lights[{li}]"
        name = node.get("name") or light.get("name") or where
        kind = light.get("type")
        if kind not in ("point", "spot", "directional"):
            raise SceneError(self.src, f"{where}.type", f"expected point, spot or directional, got {kind!r}")
        intensity = float(light.get("intensity", 1.0))
        color = tuple(float(c) * intensity for c in light.get("color", [1.0, 1.0, 1.0])[:3])
        if "range" in light and not self._range_warned:  # once a file: Blender writes it on every light
            warn(self.src, where, "a light's range is ignored: warprt's lights reach every distance")
            self._range_warned = True
        axis = world[:3, :3] @ [0.0, 0.0, -1.0]
        direction = tuple(float(x) for x in axis / np.linalg.norm(axis))
        position = tuple(float(x) for x in world[:3, 3])
        if kind == "directional":
            return Light(position=None, color=color, type=kind, direction=direction, falloff="inverse_square",
                         name=name)
        if kind == "point":
            return Light(position=position, color=color, falloff="inverse_square", name=name)
        spot = light.get("spot", {})
        outer = float(spot.get("outerConeAngle", math.pi / 4))
        inner = float(spot.get("innerConeAngle", 0.0))
        if not 0.0 <= inner < outer <= math.pi / 2:
            raise SceneError(self.src, f"{where}.spot", f"expected 0 <= innerConeAngle < outerConeAngle <= pi/2, "
                                                        f"got {inner:g} and {outer:g}")
        return Light(position=position, color=color, type="spot", direction=direction,
                     cutoff_angle=math.degrees(outer), beam_width=math.degrees(inner), falloff="inverse_square",
                     name=name)

    def _instances(self, node) -> list[np.ndarray]:
        ext = node.get("extensions", {}).get("EXT_mesh_gpu_instancing")
        if not ext:
            return [np.eye(4)]
        at = ext.get("attributes", {})
        n = max(self.doc["accessors"][a]["count"] for a in at.values())
        t = self.accessor(at["TRANSLATION"]) if "TRANSLATION" in at else np.zeros((n, 3))
        r = self.accessor(at["ROTATION"]) if "ROTATION" in at else np.tile([0.0, 0.0, 0.0, 1.0], (n, 1))
        s = self.accessor(at["SCALE"]) if "SCALE" in at else np.ones((n, 3))
        return [_node_matrix({"translation": t[k], "rotation": r[k], "scale": s[k]}) for k in range(n)]

    def _primitive(self, prim, placement, materials, tex_coords, name) -> MeshPart | None:
        mode = prim.get("mode", 4)
        if mode not in (4, 5, 6):
            warn(self.src, name, "points and lines are not rendered")
            return None
        if "extensions" in prim and "KHR_draco_mesh_compression" in prim["extensions"]:
            raise SceneError(self.src, name, "Draco-compressed geometry is not supported; export without compression")
        at = prim["attributes"]
        p = self.accessor(at["POSITION"])
        idx = self.accessor(prim["indices"]).reshape(-1) if "indices" in prim else np.arange(len(p))
        if mode == 4:
            faces = idx[: len(idx) // 3 * 3].reshape(-1, 3)
        elif mode == 5:  # a strip: every other triangle turned over to keep the winding
            k = np.arange(max(len(idx) - 2, 0))
            faces = np.stack([idx[k], idx[k + 1 + (k & 1)], idx[k + 2 - (k & 1)]], 1)
        else:  # a fan
            k = np.arange(1, max(len(idx) - 1, 1))
            faces = np.stack([np.full(len(k), idx[0]), idx[k], idx[k + 1]], 1)
        if len(faces) and (faces.min() < 0 or faces.max() >= len(p)):
            raise SceneError(self.src, name, f"a face refers to a vertex that does not exist (the primitive has {len(p)})")
        material = prim.get("material", -1)
        tex_coord = tex_coords[material] if material >= 0 else 0
        uv = self.accessor(at[f"TEXCOORD_{tex_coord}"])[:, :2].copy() if f"TEXCOORD_{tex_coord}" in at else None
        if uv is not None:
            uv[:, 1] = 1.0 - uv[:, 1]  # glTF's v runs down the image; ours up
        normals = self.accessor(at["NORMAL"])[:, :3] if "NORMAL" in at else None
        colors = self.accessor(at["COLOR_0"])[:, :3] if "COLOR_0" in at else None
        faces, (used,) = weld_corners([faces.astype(np.int64)], len(p))
        m = placement[:3, :3]
        vertices = p[used] @ m.T + placement[:3, 3]
        part = MeshPart(name, vertices, faces, np.full(len(faces), material, np.int64),
                        None if uv is None else uv[used], None if colors is None else np.clip(colors[used], 0.0, None))
        if normals is not None:
            part.normals = unit_rows(normals[used] @ np.linalg.inv(m))[faces]
        if np.linalg.det(m) < 0:  # a mirroring node turns the winding over
            part.faces = np.ascontiguousarray(part.faces[:, ::-1])
            part.normals = None if part.normals is None else np.ascontiguousarray(part.normals[:, ::-1])
        return part


def _roots(doc) -> list[int]:
    children = {c for n in doc.get("nodes", []) for c in n.get("children", [])}
    return [i for i in range(len(doc.get("nodes", []))) if i not in children]


def _node_matrix(node) -> np.ndarray:
    """The node's local transform, column vectors (p' = M p), from its matrix or its T R S."""
    if "matrix" in node:
        return np.asarray(node["matrix"], np.float64).reshape(4, 4).T
    t = np.asarray(node.get("translation", [0, 0, 0]), np.float64)
    x, y, z, w = (float(c) for c in node.get("rotation", [0, 0, 0, 1]))
    norm = math.sqrt(x * x + y * y + z * z + w * w) or 1.0
    x, y, z, w = x / norm, y / norm, z / norm, w / norm
    s = np.asarray(node.get("scale", [1, 1, 1]), np.float64)
    r = np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                  [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                  [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])
    m = np.eye(4)
    m[:3, :3] = r * s
    m[:3, 3] = t
    return m


def _texture_transform(info) -> tuple[tuple, int]:
    """KHR_texture_transform as our uv map (glTF's uv space has v down: the map is conjugated by the
    flip v -> 1 - v), and the texture coordinate set."""
    ext = info.get("extensions", {}).get("KHR_texture_transform")
    tex_coord = info.get("texCoord", 0)
    if not ext:
        return (1.0, 0.0, 0.0, 0.0, 1.0, 0.0), tex_coord
    ox, oy = ext.get("offset", [0.0, 0.0])
    rotation = ext.get("rotation", 0.0)
    sx, sy = ext.get("scale", [1.0, 1.0])
    tex_coord = ext.get("texCoord", tex_coord)
    c, s = math.cos(rotation), math.sin(rotation)
    m = np.array([[c * sx, s * sy, ox], [-s * sx, c * sy, oy], [0.0, 0.0, 1.0]])  # T R S, as the extension defines
    flip = np.array([[1.0, 0.0, 0.0], [0.0, -1.0, 1.0], [0.0, 0.0, 1.0]])
    o = flip @ m @ flip
    return tuple(float(x) for x in (*o[0], *o[1])), tex_coord
