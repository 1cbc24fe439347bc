"""warprt: a small, correct, fast Whitted ray tracer whose kernels are NVIDIA Warp code.

    scene = warprt.load_scene("scene.toml")
    image, stats = warprt.render(scene)
    rows = warprt.batch("orbit.toml", "out")      # many frames from a job file (warprt.dataset)

The data flows one way, and so do the imports: scene/ (file -> Scene) -> geometry/ (float32
triangles relative to the objects' centre, BVH) -> kernels/ (Warp functions) -> image/ (a frame on the host) -> dataset/ (many
frames) -> cli.py.
"""

from .errors import SceneError, SceneWarning
from .scene import Camera, EffectSet, Light, Material, RenderSettings, Scene, SceneObject, load_scene

__version__ = "0.1.0"

__all__ = ["Camera", "EffectSet", "Light", "Material", "RenderResult", "RenderSettings", "RenderStats",
           "Scene", "SceneError", "SceneObject", "SceneWarning", "batch", "load_scene", "render", "__version__"]

_RENDERER_NAMES = ("render", "RenderResult", "RenderStats")


def __getattr__(name):
    """The renderer (and batch, which uses it) is imported on first use: importing Warp takes about
    0.4 s, which reading or checking a scene file (and Mitsuba's reference) should not pay."""
    if name in _RENDERER_NAMES:
        from . import image

        for n in _RENDERER_NAMES:
            globals()[n] = getattr(image, n)
        return globals()[name]
    if name == "batch":  # the function; the subpackage it lives in is warprt.dataset
        from .dataset import batch

        globals()["batch"] = batch
        return batch
    raise AttributeError(f"module 'warprt' has no attribute '{name}'")
