"""The tracer's first hits, for comparison with the Z-buffer's: the face the trace kernel's first query
hits at every sample, from a kernel of the test's own (the same camera ray, origin and max_t, without
shading), so the comparison leaves the tracer as it is."""

import numpy as np
import warp as wp

from shortcuts import probe_camera, probe_ray, probe_samples
from warprt.geometry import Geometry, SceneData
from warprt.image import launch_bands
from warprt.kernels import CameraData, init_warp


@wp.kernel(enable_backward=False)
def primary_faces_kernel(s: SceneData, c: CameraData, k: int, samples: int, first_pixel: int,
                         face: wp.array(dtype=wp.int32)):
    pixel = first_pixel + wp.tid()
    x = pixel % c.width
    row = pixel / c.width
    for sample in range(samples):
        q = wp.mesh_query_ray(s.mesh, c.eye, probe_ray(c, x, row, sample, samples, k), 1.0e30)
        f = int(-1)
        if q.result:
            f = q.face
        face[pixel * samples + sample] = f


def traced_faces(scene, *, geometry: Geometry | None = None, threads: int = 2) -> np.ndarray:
    """The face the ray tracer's primary ray hits at every sample, (height, width, samples), -1 for a miss;
    samples as the tracer takes them (k*k with supersampling, else the centre)."""
    init_warp()
    cam = scene.camera
    k, samples = probe_samples(scene)
    geom = geometry or Geometry(scene)
    assert geom.mesh is not None, "the tracer's first hits need a Geometry with its BVH"
    face = wp.empty(cam.width * cam.height * samples, dtype=wp.int32, device="cpu")
    c = probe_camera(scene, geom)
    launch_bands(primary_faces_kernel, lambda first: [geom.data, c, k, samples, first, face],
                 cam.width * cam.height, threads, max(16, 8 * threads), "cpu")
    return face.numpy().reshape(cam.height, cam.width, samples)
