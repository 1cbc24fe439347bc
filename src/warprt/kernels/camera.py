"""The cameras the kernels see: the tracer's pinhole (CameraData: the seed's basis and the eye, float32,
relative to the geometry's frame origin) and the rasterizer's projection of it (RasterCamera, float64)."""

from __future__ import annotations

from .._warp import wp


@wp.struct
class CameraData:
    """The seed's camera basis and image-plane size, and the eye relative to the frame origin (where
    the camera rays start: 0 for the frame the geometry was built for)."""

    eye: wp.vec3
    x_e: wp.vec3
    y_e: wp.vec3
    z_e: wp.vec3
    d_f: float
    h: float
    w: float
    width: int
    height: int


def camera_data(basis, eye=(0.0, 0.0, 0.0)) -> CameraData:
    """From a scene.CameraBasis and the float32 eye relative to the frame origin (Geometry.eye_offset)."""
    c = CameraData()
    c.eye = wp.vec3(*map(float, eye))
    c.x_e, c.y_e, c.z_e = (wp.vec3(*map(float, v)) for v in (basis.x_e, basis.y_e, basis.z_e))
    c.d_f, c.h, c.w = float(basis.d_f), float(basis.h), float(basis.w)
    c.width, c.height = int(basis.width), int(basis.height)
    return c


@wp.func
def camera_of(eye: wp.vec3, center: wp.vec3, up: wp.vec3, fovy: float, near: float, width: int,
              height: int) -> CameraData:
    """The CameraData of a camera, made in Warp (float32, differentiable in eye, center, up and fovy, in
    degrees) as scene.camera_basis makes it on the host in float64: z_e = (eye - center) / |eye - center|,
    x_e = (up x z_e) / |up x z_e|, y_e = z_e x x_e, d_f = near, h = 2 near tan(fovy / 2), w = h width /
    height. The gradient's camera: its rays and edges move with it."""
    z_e = wp.normalize(eye - center)
    x_e = wp.normalize(wp.cross(up, z_e))
    h = 2.0 * near * wp.tan(wp.radians(fovy) * 0.5)
    return CameraData(eye, x_e, wp.cross(z_e, x_e), z_e, near, h, h * float(width) / float(height), width, height)


@wp.func
def image_plane_point(c: CameraData, px: float, py: float) -> wp.vec3:
    """The point (px, py) of the image plane (0 to 1 from its lower-left corner) relative to the eye:
    -d_f z_e + h (py - 1/2) y_e + w (px - 1/2) x_e, affine in (px, py): what a camera ray aims at."""
    return (-c.d_f) * c.z_e + c.h * (py - 0.5) * c.y_e + c.w * (px - 0.5) * c.x_e


@wp.func
def camera_ray(c: CameraData, x: int, row: int, sx: float, sy: float) -> wp.vec3:
    """Unit direction d = -d_f z_e + h((y+sy)/h_p - 1/2) y_e + w((x+sx)/w_p - 1/2) x_e (image_plane_point),
    y = h_p - 1 - row counted from the bottom, so row 0 of the image is the top."""
    y = float(c.height - 1 - row)
    return wp.normalize(image_plane_point(c, (float(x) + sx) / float(c.width), (y + sy) / float(c.height)))


@wp.func
def sample_offset(sample: int, k: int) -> wp.vec2:
    """Where sample j k + i of a pixel's k x k stratified samples lies in the pixel: the centre of
    stratum (i, j), counted from the pixel's lower-left corner."""
    sx = (float(sample % k) + 0.5) / float(k)
    sy = (float(sample / k) + 0.5) / float(k)
    return wp.vec2(sx, sy)


@wp.func
def sample_position(pixel: int, i: int, step: wp.float64) -> wp.float64:
    """Where stratum i of a pixel's k strata along one axis has its centre, in float64 pixel units:
    pixel + (i + 1/2) / k, with step = 1 / k. Where the rasterizer samples, and the ideal line a
    mirror's ray is measured against."""
    return wp.float64(pixel) + (wp.float64(i) * step + wp.float64(0.5) * step)


@wp.struct
class RasterCamera:
    """The camera basis in float64 and the projection onto continuous pixel coordinates
    (X, Y) = (c_x + f_x x/z, c_y + f_y y/z), y counted up from the bottom edge like the tracer, of
    points relative to the eye, itself the tracer's float32 ray origin (eye - frame origin), exactly, in float64."""

    eye: wp.vec3d
    x_e: wp.vec3d
    y_e: wp.vec3d
    z_e: wp.vec3d
    f_x: wp.float64  # d_f * width / w: pixels per unit of x/z
    f_y: wp.float64
    c_x: wp.float64  # width / 2
    c_y: wp.float64
    z_clip: wp.float64  # clip distance in front of the eye
    margin: wp.float64  # hybrid.MARGIN_PX when the rasterizer tracks uncertain samples for the hybrid, else 0
    width: int
    height: int


def raster_camera(basis, z_clip: float, margin: float = 0.0, eye=(0.0, 0.0, 0.0)) -> RasterCamera:
    c = RasterCamera()
    c.eye = wp.vec3d(*map(float, eye))
    c.x_e, c.y_e, c.z_e = (wp.vec3d(*map(float, v)) for v in (basis.x_e, basis.y_e, basis.z_e))
    c.f_x = wp.float64(basis.d_f * basis.width / basis.w)
    c.f_y = wp.float64(basis.d_f * basis.height / basis.h)
    c.c_x = wp.float64(basis.width / 2.0)
    c.c_y = wp.float64(basis.height / 2.0)
    c.z_clip = wp.float64(z_clip)
    c.margin = wp.float64(margin)
    c.width, c.height = int(basis.width), int(basis.height)
    return c
