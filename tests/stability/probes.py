"""Small Warp kernels that drive the renderer's own BVH and secondary-ray functions on bulk rays,
and the file where the stability suite records what it measured (tests/_artifacts/stability.json)."""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np
import warp as wp

from warprt.geometry import SceneData
from warprt.scene import DEFAULT_MATERIAL, Camera, RenderSettings, Scene, SceneObject
from warprt.kernels import OFFSET_SCALE, init_warp, make_surface, offset_ray_origin, refract, triangle, unit_normal

init_warp()

ARTIFACT = Path(__file__).resolve().parents[1] / "_artifacts" / "stability.json"
DEVICE = "cpu"  # the renderer's default device, where Geometry builds the BVH
EPS32 = 2.0**-24


def record(key: str, figures: dict):
    """Print a property's measured figures and keep them in the suite's JSON artifact."""
    print(f"\n[stability] {key}: {json.dumps(figures, default=float)}")
    ARTIFACT.parent.mkdir(parents=True, exist_ok=True)
    data = json.loads(ARTIFACT.read_text()) if ARTIFACT.exists() else {}
    data[key] = figures
    tmp = ARTIFACT.with_suffix(".tmp")
    tmp.write_text(json.dumps(data, indent=1, sort_keys=True, default=float))
    os.replace(tmp, ARTIFACT)


def mesh_scene(objects: dict, eye, center=None) -> Scene:
    """A Scene built through the Python API from {name: (world vertices, faces)}."""
    eye = tuple(float(x) for x in eye)
    center = tuple(float(x) for x in (center if center is not None else np.asarray(eye) - [0.0, 0.0, 1.0]))
    objs = [SceneObject(n, np.asarray(v, np.float64), np.asarray(f, np.int64), "default") for n, (v, f) in objects.items()]
    return Scene(Camera(eye=eye, center=center), RenderSettings(), [], {"default": DEFAULT_MATERIAL}, objs, "<stability>")


@wp.kernel
def closest_hit(mesh: wp.uint64, origins: wp.array(dtype=wp.vec3), dirs: wp.array(dtype=wp.vec3),
                t_out: wp.array(dtype=float), face_out: wp.array(dtype=int)):
    i = wp.tid()
    q = wp.mesh_query_ray(mesh, origins[i], dirs[i], 1.0e30)
    if q.result:
        t_out[i] = q.t
        face_out[i] = q.face
    else:
        t_out[i] = -1.0
        face_out[i] = -1


def cast(mesh_id, origins: np.ndarray, dirs: np.ndarray):
    """Nearest hit of each float32 ray on the mesh: (t, face), -1 where the ray escapes."""
    n = len(origins)
    t = wp.empty(n, dtype=float, device=DEVICE)
    face = wp.empty(n, dtype=int, device=DEVICE)
    o = wp.array(np.ascontiguousarray(origins, np.float32), dtype=wp.vec3, device=DEVICE)
    d = wp.array(np.ascontiguousarray(dirs, np.float32), dtype=wp.vec3, device=DEVICE)
    wp.launch(closest_hit, dim=n, inputs=[mesh_id, o, d, t, face], device=DEVICE)
    return t.numpy(), face.numpy()


def surface_tables(mesh, points, indices, n_tri: int) -> SceneData:
    """The SceneData fields the renderer's surface() reads, for a bare triangle set (flat, material 0)."""
    s = SceneData()
    s.mesh = mesh.id
    s.points, s.indices = points, indices
    s.tri_material = wp.zeros(n_tri, dtype=wp.int32, device=DEVICE)
    s.tri_smooth = wp.zeros(n_tri, dtype=wp.int32, device=DEVICE)
    s.normals = wp.zeros(1, dtype=wp.vec3, device=DEVICE)
    for name in ("ka", "kd", "ks", "kr", "light_pos", "light_color"):
        setattr(s, name, wp.zeros(1, dtype=wp.vec3, device=DEVICE))
    s.shininess = wp.zeros(1, dtype=float, device=DEVICE)
    return s


surface = make_surface(False)


@wp.kernel
def offset_probe(s: SceneData, origin: wp.array(dtype=wp.vec3), target: wp.array(dtype=wp.vec3),
                 light: wp.array(dtype=wp.vec3), err_scale: float, out: wp.array(dtype=wp.vec4i)):
    """Triangle f is alone in BVH group f. A ray from origin[f] towards target[f] hits it; from that
    hit, as the tracer does (surface(), offset_ray_origin()), spawn the mirror ray and a shadow ray
    to light[f]. out[f] = (hit, mirror ray re-hits f, shadow ray cast, shadow ray blocked by f).
    err_scale multiplies the renderer's error bound (1 = as rendered)."""
    f = wp.tid()
    root = wp.mesh_get_group_root(s.mesh, f)
    d = wp.normalize(target[f] - origin[f])
    q = wp.mesh_query_ray(s.mesh, origin[f], d, 1.0e30, root)
    if not q.result:
        out[f] = wp.vec4i(0, 0, 0, 0)
        return
    hit = surface(s, q.face, q.u, q.v, q.normal, d)
    err = hit.err * err_scale
    r = wp.normalize(d - 2.0 * wp.dot(d, hit.n) * hit.n)
    q2 = wp.mesh_query_ray(s.mesh, offset_ray_origin(hit.p, err, hit.ng, r), r, 1.0e30, root)
    cast_shadow = int(0)
    blocked = int(0)
    L = wp.normalize(light[f] - hit.p)
    if wp.dot(hit.n, L) > 0.0:  # the shading's own condition for tracing a shadow ray
        cast_shadow = 1
        o = offset_ray_origin(hit.p, err, hit.ng, L)
        to_light = light[f] - o
        dist = wp.length(to_light)
        if wp.mesh_query_ray_anyhit(s.mesh, o, to_light / dist, dist, root):
            blocked = 1
    out[f] = wp.vec4i(1, wp.where(q2.result, 1, 0), cast_shadow, blocked)


def run_offset_probe(s: SceneData, origin, target, light, scale: float) -> np.ndarray:
    """offset_probe with the error bound at ``scale`` times its analytic value (OFFSET_SCALE as rendered)."""
    n = len(origin)
    out = wp.empty(n, dtype=wp.vec4i, device=DEVICE)
    arrays = [wp.array(np.ascontiguousarray(a, np.float32), dtype=wp.vec3, device=DEVICE) for a in (origin, target, light)]
    wp.launch(offset_probe, dim=n, inputs=[s, *arrays, scale / OFFSET_SCALE, out], device=DEVICE)
    return out.numpy()


@wp.kernel
def refraction_probe(s: SceneData, origin: wp.array(dtype=wp.vec3), target: wp.array(dtype=wp.vec3), eta: float,
                     err_scale: float, out: wp.array(dtype=wp.vec3i)):
    """Triangle f alone in BVH group f, a dielectric of index eta on its winding's back side. A ray
    from origin[f] towards target[f] hits it; from that hit, as the tracer does (surface(), the side
    from the winding, refract(), offset_ray_origin()), spawn the refracted ray. out[f] = (hit, a
    refracted ray exists, it re-hits f). err_scale multiplies the renderer's error bound."""
    f = wp.tid()
    root = wp.mesh_get_group_root(s.mesh, f)
    d = wp.normalize(target[f] - origin[f])
    q = wp.mesh_query_ray(s.mesh, origin[f], d, 1.0e30, root)
    if not q.result:
        out[f] = wp.vec3i(0, 0, 0)
        return
    hit = surface(s, q.face, q.u, q.v, q.normal, d)
    p0, p1, p2 = triangle(s, q.face)
    eta_rel = eta
    if not (wp.dot(hit.ng, unit_normal(p0, p1, p2)) > 0.0):  # from inside: leaving the glass
        eta_rel = 1.0 / eta
    t, transmits = refract(d, hit.ng, eta_rel)
    if not transmits:
        out[f] = wp.vec3i(1, 0, 0)
        return
    t = wp.normalize(t)
    q2 = wp.mesh_query_ray(s.mesh, offset_ray_origin(hit.p, hit.err * err_scale, hit.ng, t), t, 1.0e30, root)
    out[f] = wp.vec3i(1, 1, wp.where(q2.result, 1, 0))


def run_refraction_probe(s: SceneData, origin, target, eta: float, scale: float) -> np.ndarray:
    """refraction_probe with the error bound at ``scale`` times its analytic value (OFFSET_SCALE as rendered)."""
    n = len(origin)
    out = wp.empty(n, dtype=wp.vec3i, device=DEVICE)
    arrays = [wp.array(np.ascontiguousarray(a, np.float32), dtype=wp.vec3, device=DEVICE) for a in (origin, target)]
    wp.launch(refraction_probe, dim=n, inputs=[s, *arrays, float(eta), scale / OFFSET_SCALE, out], device=DEVICE)
    return out.numpy()
