"""The tracer's first hits, for comparison with the Z-buffer's: the face the trace kernel's first query
hits at every sample, from a kernel of the test's own (the same camera ray, origin and max_t, without
shading), so the comparison leaves the tracer as it is."""

import math

import numpy as np
import warp as wp

from warprt.geometry import Geometry, SceneData
from warprt.image import launch_bands
from warprt.kernels import CameraData, camera_data, camera_ray, init_warp, sample_offset
from warprt.scene import camera_basis, resolve_effects


@wp.kernel(enable_backward=False)
def primary_faces_kernel(s: SceneData, c: CameraData, k: int, samples: int, first_pixel: int,
                         face: wp.array(dtype=wp.int32)):
    pixel = first_pixel + wp.tid()
    x = pixel % c.width
    row = pixel / c.width
    for sample in range(samples):
        offset = wp.vec2(0.5, 0.5)
        if samples > 1:
            offset = sample_offset(sample, k)
        q = wp.mesh_query_ray(s.mesh, c.eye, camera_ray(c, x, row, offset[0], offset[1]), 1.0e30)
        f = int(-1)
        if q.result:
            f = q.face
        face[pixel * samples + sample] = f


def traced_faces(scene, *, geometry: Geometry | None = None, threads: int = 2) -> np.ndarray:
    """The face the ray tracer's primary ray hits at every sample, (height, width, samples), -1 for a miss;
    samples as the tracer takes them (k*k with supersampling, else the centre)."""
    init_warp()
    cam = scene.camera
    k = math.isqrt(scene.render.spp)
    samples = k * k if resolve_effects(scene).supersampling else 1
    geom = geometry or Geometry(scene)
    assert geom.mesh is not None, "the tracer's first hits need a Geometry with its BVH"
    face = wp.empty(cam.width * cam.height * samples, dtype=wp.int32, device="cpu")
    c = camera_data(camera_basis(cam), geom.eye_offset(cam.eye))
    launch_bands(primary_faces_kernel, lambda first: [geom.data, c, k, samples, first, face],
                 cam.width * cam.height, threads, max(16, 8 * threads), "cpu")
    return face.numpy().reshape(cam.height, cam.width, samples)
