"""warprt: a small, correct, fast Whitted ray tracer whose kernels are NVIDIA Warp code.

    scene = warprt.load_scene("scene.toml")        # or warprt.load_dict({...}): the file's schema as a dict
    image, stats = warprt.render(scene)
    r = warprt.Renderer(scene)                    # frames of one scene: the BVH and caches kept
    r.params["materials.red.kd"] = [0.9, 0.1, 0.1]
    image, stats = r.render()
    rows = warprt.batch("orbit.toml", "out")      # many frames from a job file (warprt.dataset)

The data flows one way, and so do the imports: scene/ (file -> Scene) -> geometry/ (float32
triangles relative to the objects' centre, BVH) -> kernels/ (Warp functions) -> image/ (a frame on the host) -> dataset/ (many
frames) -> cli.py.
"""

from typing import TYPE_CHECKING

from .errors import SceneError, SceneWarning
from .options import RenderOptions
from .scene import Camera, Light, Material, RenderSettings, Scene, SceneObject, load_dict, load_scene

if TYPE_CHECKING:
    from .dataset import batch
    from .image import Renderer, render

__version__ = "0.1.0"

__all__ = ["Camera", "Light", "Material", "RenderOptions", "RenderSettings", "Renderer", "Scene", "SceneError",
           "SceneObject", "SceneWarning", "batch", "load_dict", "load_scene", "render", "__version__"]


def __getattr__(name):
    """render, Renderer and batch, imported on first use: the one place warprt defers Warp's import
    (about 0.2 s), which reading or checking a scene (warprt info, Mitsuba's reference) does not need."""
    if name == "render":
        from .image import render as value
    elif name == "Renderer":
        from .image import Renderer as value
    elif name == "batch":
        from .dataset import batch as value
    else:
        raise AttributeError(f"module 'warprt' has no attribute '{name}'")
    globals()[name] = value
    return value
