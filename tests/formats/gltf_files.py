"""glTF files written by hand for the tests: a JSON document whose arrays become accessors in one
base64 buffer, so the file is what an exporter writes, read back by warprt's reader."""

from __future__ import annotations

import base64
import json
import math

import numpy as np

_TYPES = {1: "SCALAR", 2: "VEC2", 3: "VEC3", 4: "VEC4"}
_COMPONENTS = {np.dtype(np.float32): 5126, np.dtype(np.uint16): 5123, np.dtype(np.uint32): 5125}


class Gltf:
    """A glTF document under construction: add arrays (accessors), meshes, nodes; write() saves it."""

    def __init__(self):
        self.doc = {"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": []}], "nodes": [], "meshes": [],
                    "accessors": [], "bufferViews": [], "buffers": []}
        self.blob = bytearray()

    def accessor(self, a: np.ndarray) -> int:
        a = np.ascontiguousarray(a)
        while len(self.blob) % 4:
            self.blob.append(0)
        self.doc["bufferViews"].append({"buffer": 0, "byteOffset": len(self.blob), "byteLength": a.nbytes})
        self.blob.extend(a.tobytes())
        width = 1 if a.ndim == 1 else a.shape[1]
        acc = {"bufferView": len(self.doc["bufferViews"]) - 1, "componentType": _COMPONENTS[a.dtype],
               "count": len(a), "type": _TYPES[width]}
        if a.dtype == np.float32 and width == 3:
            acc["min"], acc["max"] = a.min(0).tolist(), a.max(0).tolist()
        self.doc["accessors"].append(acc)
        return len(self.doc["accessors"]) - 1

    def mesh(self, vertices, faces, uv=None, material=None) -> int:
        attributes = {"POSITION": self.accessor(np.asarray(vertices, np.float32))}
        if uv is not None:
            attributes["TEXCOORD_0"] = self.accessor(np.asarray(uv, np.float32))
        prim = {"attributes": attributes, "indices": self.accessor(np.asarray(faces, np.uint32).reshape(-1))}
        if material is not None:
            prim["material"] = material
        self.doc["meshes"].append({"primitives": [prim]})
        return len(self.doc["meshes"]) - 1

    def node(self, root: bool = True, **fields) -> int:
        self.doc["nodes"].append(fields)
        index = len(self.doc["nodes"]) - 1
        if root:
            self.doc["scenes"][0]["nodes"].append(index)
        return index

    def add(self, key: str, item: dict) -> int:
        self.doc.setdefault(key, []).append(item)
        return len(self.doc[key]) - 1

    def light(self, item: dict) -> int:
        self.doc.setdefault("extensionsUsed", ["KHR_lights_punctual"])
        lights = self.doc.setdefault("extensions", {}).setdefault("KHR_lights_punctual", {"lights": []})["lights"]
        lights.append(item)
        return len(lights) - 1

    def write(self, path):
        self.doc["buffers"] = [{"byteLength": len(self.blob),
                                "uri": "data:application/octet-stream;base64," + base64.b64encode(bytes(self.blob)).decode()}]
        path.write_text(json.dumps(self.doc))
        return path


def quaternion(axis, degrees) -> list:
    """glTF's rotation (x, y, z, w) turning by ``degrees`` about ``axis``."""
    axis = np.asarray(axis, np.float64) / np.linalg.norm(axis)
    half = math.radians(degrees) / 2
    return [*(axis * math.sin(half)).tolist(), math.cos(half)]


def quaternion_product(a, b) -> list:
    """a b for glTF (x, y, z, w) quaternions: b's turn first, then a's."""
    (ax, ay, az, aw), (bx, by, bz, bw) = a, b
    return [aw * bx + ax * bw + ay * bz - az * by, aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw, aw * bw - ax * bx - ay * by - az * bz]


def rotation_matrix(axis, degrees) -> np.ndarray:
    """Rodrigues' formula: the turn by ``degrees`` about ``axis`` (column vectors)."""
    k = np.asarray(axis, np.float64) / np.linalg.norm(axis)
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    t = math.radians(degrees)
    return np.eye(3) + math.sin(t) * K + (1 - math.cos(t)) * K @ K


def box(center, size):
    """A closed box's 8 corners and 12 triangles, wound outward."""
    c, h = np.asarray(center, np.float64), np.asarray(size, np.float64) / 2
    v = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]) * h + c
    f = [[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
         [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]]
    return v, np.array(f)


def usd_box(stage, prim_path: str, center, size):
    """The same box as a UsdGeom.Mesh of triangles at prim_path on a pxr stage, for the USD tests."""
    from pxr import Gf, UsdGeom

    v, f = box(center, size)
    mesh = UsdGeom.Mesh.Define(stage, prim_path)
    mesh.CreatePointsAttr([Gf.Vec3f(*map(float, p)) for p in v])
    mesh.CreateFaceVertexCountsAttr([3] * len(f))
    mesh.CreateFaceVertexIndicesAttr([int(i) for i in f.reshape(-1)])
    return mesh
