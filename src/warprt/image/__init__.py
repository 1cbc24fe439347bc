"""The host side of a frame: the Renderer that owns a scene's frames and render(), the one-shot over it
(renderer.py), its plan and policies (plan.py), the caches it keeps (caches.py) and the parameters it
changes between frames (params.py); launching bands (launch.py), the stats (stats.py), the Z-buffer
(zbuffer.py), the planar mirrors' virtual cameras (mirrors.py), the AOVs (aovs.py), memory (memory.py),
image files (film.py), the progress line (progress.py) and render.adaptive's refinement (adaptive.py); the gradient: its record (grad_record.py), its
parameters (grad_params.py), its replay and backward() (grad.py), a smooth object's vertex normals from its moving
points (grad_normals.py), and its boundary term (grad_edges.py: the
edges camera rays see; grad_shadow_edges.py: hard shadows' edges; grad_checker_edges.py: a checker's squares;
grad_spot_edges.py: a spot's hard cone; grad_mirror_edges.py: edges and shadows seen in planar mirrors;
grad_edge_points.py: where they lie in the image; grad_mesh_edges.py: the meshes' edges and silhouettes).
"""

from ..options import RenderOptions
from .adaptive import refined_pixels
from .aovs import AOVS, check_aovs
from .caches import FrameCaches, LightHistory
from .grad import Replay, build_replay, pose_points, replay_focus, replay_image
from .grad_edge_points import EdgePoints, edge_points, segment_points
from .grad_edges import Boundary, EdgeFrame, boundary, edge_sides, edge_speeds
from .grad_mesh_edges import MeshEdges, camera_edges, mesh_edges
from .grad_mirror_edges import (MAX_CHAINS, ChainFaces, MirrorChain, MirroredSegments, chain_faces, mirror_chains,
                                mirror_planes, mirrored_speeds)
from .grad_shadow_edges import (ShadowSegments, ShadowSources, light_sides, shadow_rows, shadow_segments, shadow_sources,
                                shadow_speeds)
from .grad_record import Record, record_first_hits
from .film import aov_paths, partial_files, read_aovs, read_image, to_srgb8, write_image
from .launch import bands_of, default_threads, launch_bands
from .mirrors import MirrorFrame
from .params import Pose, SceneParameters, object_poses
from .plan import mirrors_from_rasters, raster_is_cheaper, shadows_from_grid
from .renderer import Renderer, check_finite, render, render_zbuffer
from .stats import RenderResult, RenderStats
from .zbuffer import ZBuffer, eye_on_surface

__all__ = ["AOVS", "Record", "Replay", "build_replay", "FrameCaches", "LightHistory", "MirrorFrame", "Pose", "RenderOptions", "RenderResult", "RenderStats",
           "Renderer", "SceneParameters", "ZBuffer", "aov_paths", "bands_of", "check_aovs", "check_finite",
           "default_threads", "eye_on_surface", "launch_bands", "mirrors_from_rasters", "object_poses", "partial_files", "pose_points",
           "raster_is_cheaper", "read_aovs", "read_image", "record_first_hits", "render", "replay_focus", "replay_image", "render_zbuffer", "shadows_from_grid",
           "to_srgb8", "write_image"]
__all__ += ["refined_pixels"]  # render.adaptive
__all__ += ["EdgeFrame", "EdgePoints", "camera_edges", "edge_points", "edge_sides", "edge_speeds"]  # backward(edges=True)
__all__ += ["Boundary", "MeshEdges", "ShadowSegments", "ShadowSources", "boundary", "light_sides", "mesh_edges",
            "segment_points", "shadow_rows", "shadow_segments", "shadow_sources", "shadow_speeds"]  # and hard shadows' edges
__all__ += ["MAX_CHAINS", "ChainFaces", "MirrorChain", "MirroredSegments", "chain_faces", "mirror_chains", "mirror_planes",
            "mirrored_speeds"]  # and both seen in planar mirrors
from .grad_glass_edges import (LINES, MAX_GLASS_DEPTH, glass_cone_lights, glass_crossings, glass_terms,  # noqa: E402
                               tree_walk)

__all__ += ["LINES", "MAX_GLASS_DEPTH", "glass_cone_lights", "glass_crossings", "glass_terms",
            "tree_walk"]  # and those seen through glass
