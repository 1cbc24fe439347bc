"""What a Renderer keeps from one frame for the next (FrameCaches): each cache a declared field with the
change that invalidates it, so that the path a frame takes depends only on the Renderer's own history."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

LIGHT_SETS_KEPT = 64  # lights moving every frame: no set of them stays long enough to amortize a grid
VIEWS_COUNTED = 64  # a moving camera: no view stays long enough to amortize virtual cameras
SHADOW_GRIDS_KEPT = 2  # moving lights: the memory of two grids at most
EYE_TESTS_KEPT = 16  # a camera path: keep the eye-on-a-surface memo small


class FrameCounter:
    """How many frames have been rendered with each key (a light set, a view): the shortcut policies
    pay a build once a key has come back, so that it is paid by the frames after it."""

    def __init__(self, limit: int):
        self.limit = limit
        self.frames: dict = {}

    def record(self, key) -> int:
        """Count one more frame with ``key``; how many there have been, this one included."""
        if key not in self.frames and len(self.frames) >= self.limit:
            self.frames.clear()
        self.frames[key] = self.frames.get(key, 0) + 1
        return self.frames[key]


class LightHistory(FrameCounter):
    """The frames a Geometry has served with each set of light positions (float32, relative to its origin)."""

    def __init__(self, limit: int = LIGHT_SETS_KEPT):
        super().__init__(limit)

    def record(self, lights: np.ndarray) -> int:
        return super().record(np.asarray(lights, np.float32).tobytes())


@dataclass
class FrameCaches:
    """A Renderer's frame-to-frame state. Every entry is derived from its Geometry's triangles (and is
    keyed by whatever else it depends on: the lights, the view, which materials reflect), so a new or
    refit Geometry drops them all (``clear``); a change of colours, lights or camera leaves them, and the
    keys pick what still applies. None of them changes an image: each shortcut gives the traced answer."""

    # The shadow grid's policy: frames per light set.
    light_history: LightHistory = field(default_factory=LightHistory)
    # (float32 light positions, byte budget) -> ShadowGridBuild, at most SHADOW_GRIDS_KEPT.
    shadow_grids: dict = field(default_factory=dict)
    # The mirrors' policy: frames per view (image.mirrors.view_key).
    view_frames: FrameCounter = field(default_factory=lambda: FrameCounter(VIEWS_COUNTED))
    # view_key -> MirrorFrame (the virtual cameras' rasters), mirrors.KEEP_VIEWS within mirrors.MAX_BYTES.
    virtual_cameras: dict = field(default_factory=dict)
    # Which material slots reflect -> (planar group per triangle, planes): geometry.planar_groups.
    planar_groups: dict = field(default_factory=dict)
    # (planes, side) -> MirroredGeometry, within planar.KEEP_BYTES: geometry.mirrored_geometry.
    mirrored: dict = field(default_factory=dict)
    # (tolerance, eye) -> whether the eye is on a surface, at most EYE_TESTS_KEPT: zbuffer.eye_on_surface.
    eye_on_surface: dict = field(default_factory=dict)
    # (samples, device) -> the raster buffers of one frame, every sample clear: the virtual cameras draw
    # into them. They depend on the frame's size alone, so a change of triangles keeps them.
    raster_scratch: dict = field(default_factory=dict)

    def clear(self):
        """Drop what the triangles determine: the Geometry was rebuilt or its vertices moved."""
        scratch = self.raster_scratch
        self.__init__()
        self.raster_scratch = scratch
