"""warprt: a small, correct, fast Whitted ray tracer whose kernels are NVIDIA Warp code.

    scene = warprt.load_scene("scene.toml")
    image, stats = warprt.render(scene)
"""

import warp as _wp

# Warp's start-up banner and module-load lines are noise for a renderer's users.
_wp.config.quiet = True
_wp.config.log_level = _wp.LOG_WARNING

from .effects import EffectSet
from .errors import SceneError
from .render import RenderResult, RenderStats, render
from .scene import Camera, Light, Material, RenderSettings, Scene, SceneObject, load_scene

__version__ = "0.1.0"

__all__ = ["Camera", "EffectSet", "Light", "Material", "RenderResult", "RenderSettings", "RenderStats",
           "Scene", "SceneError", "SceneObject", "load_scene", "render", "__version__"]
