"""USD stages through pxr (usd-core): every visible Mesh prim in world space, PointInstancer copies,
UsdPreviewSurface materials and the primvars that colour and shade them.

What is read: points, faceVertexCounts/Indices, holeIndices (polygons fanned as Hydra does),
orientation, the prim's world transform; the st primvar a bound UsdUVTexture reads (through its
UsdPrimvarReader), normals (primvars:normals before the normals attribute) and displayColor, each of
any interpolation, indexed or not; diffuseColor (a value, or a UsdUVTexture with its scale and
bias), and emissiveColor (a value: the material's emission, an area light over its objects), per prim
and per GeomSubset; metersPerUnit and upAxis where the stage authors them; UsdGeomCamera prims as cameras;
UsdLux rect, disk and sphere lights as area lights (points where they have no size), distant lights,
ShapingAPI cones as spots, and cylinder lights as emitting tubes (a part with its own emissive material).
"""

from __future__ import annotations

import math
import re
from dataclasses import replace
from pathlib import Path

import numpy as np

from ...diagnostics import native_stderr, usd_messages, warn
from ...errors import SceneError, one_line
from ..dielectric_formats import dielectric_from_usd
from ..camera import FileCamera, look_from_matrix
from ..model import Light, Material
from ..placement import euler_xyz, nearest_rotation
from ..shapes import cylinder
from ..texture import Texture, image_texture
from .usdcrate import MAGIC as CRATE_MAGIC, check_crate
from . import MeshFile, MeshPart, dedupe, fan_corners, unique_name, unit_rows, weld_corners

_USD_GREY = (0.18, 0.18, 0.18)  # UsdPreviewSurface's diffuseColor when not authored
CYLINDER_LIGHT_SECTORS = 128  # a CylinderLight's tube: its area 1 - 1e-4 of the true cylinder's
_POLE_Z = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])  # +90 about x: a dome's +y pole to +z


def read_usd(path: Path) -> MeshFile:
    src = str(path)
    try:
        from pxr import Usd
    except ImportError:
        raise SceneError(src, None, "reading USD needs the usd-core package (pip install usd-core)") from None
    with open(path, "rb") as f:
        if f.read(len(CRATE_MAGIC)) == CRATE_MAGIC:
            check_crate(src, path, path.stat().st_size)
    # USD reports on fd 2 in multi-line C++ diagnostics: each becomes one warprt warning.
    native = None
    try:
        with native_stderr() as native:
            try:
                stage = Usd.Stage.Open(src)
            except Exception as e:
                raise SceneError(src, None, f"cannot open USD stage: {_pxr_message(e)}") from None
            if stage is None:
                raise SceneError(src, None, "cannot open USD stage")
            return _Stage(path, stage).mesh_file()
    except Exception as e:
        if isinstance(e, SceneError) or not type(e).__module__.startswith("pxr"):
            raise
        # USD read the layer but a value in it is damaged (a corrupt crate value, a bad array).
        raise SceneError(src, None, f"cannot read USD file: {_pxr_message(e)}") from None
    finally:
        for message in usd_messages(native.text if native else ""):
            warn(src, "USD", message)


def _plain(message: str) -> str:
    """A pxr message without its C++ namespaces and quoting."""
    message = re.sub(r"pxrInternal_[A-Za-z0-9_]*::", "", message)
    message = re.sub(r"\s*<0x[0-9a-fA-F]+>", "", message)  # object addresses: noise, and never the same twice
    return one_line(message)


def _pxr_message(e: Exception) -> str:
    """The first quoted reason in a pxr error, without its C++ namespaces."""
    try:
        text = str(e)
    except UnicodeDecodeError:  # USD's message quotes the file's own bytes, and they are not UTF-8
        text = "\n".join(_commentary(a) for a in e.args)
    found = re.findall(r": '(.*?)'\s*(?:\n|$)", text, flags=re.S)
    return _plain(found[0] if found else text)


def _commentary(error) -> str:
    try:
        return f": '{error.commentary}'"
    except (UnicodeDecodeError, AttributeError):
        return ": 'the file holds bytes that are not UTF-8 text where USD expects text'"


class _Stage:
    def __init__(self, path: Path, stage):
        from pxr import Usd, UsdGeom

        self.path, self.src, self.stage = path, str(path), stage
        # The earliest time sample: a stage animated from frame 1 has no value at the default time.
        self.time = Usd.TimeCode.EarliestTime()
        self.xforms = UsdGeom.XformCache(self.time)
        # pxr answers 0.01 (centimetres) and Y for a stage that says nothing: only what is authored counts.
        self.meters = float(UsdGeom.GetStageMetersPerUnit(stage)) if stage.HasAuthoredMetadata("metersPerUnit") else 1.0
        self.up = str(UsdGeom.GetStageUpAxis(stage)) if stage.HasAuthoredMetadata("upAxis") else None
        self.materials: list[tuple[str, Material]] = []
        self.uv_names: list[str | None] = []  # the primvar each material's texture reads
        self._index: dict[str, int] = {}

    def mesh_file(self) -> MeshFile:
        from pxr import Usd, UsdGeom, UsdLux

        prototypes, instancers = set(), []
        for prim in self.stage.Traverse(Usd.TraverseInstanceProxies()):
            if prim.IsA(UsdGeom.PointInstancer):
                targets = [str(t) for t in UsdGeom.PointInstancer(prim).GetPrototypesRel().GetTargets()]
                prototypes.update(targets)
                instancers.append((UsdGeom.PointInstancer(prim), targets))

        def is_prototype(prim) -> bool:  # drawn only where its instancer places it
            while prim and not prim.IsPseudoRoot():
                if str(prim.GetPath()) in prototypes:
                    return True
                prim = prim.GetParent()
            return False

        parts = []
        for prim in self.stage.Traverse(Usd.TraverseInstanceProxies()):
            if prim.IsA(UsdGeom.Mesh) and not is_prototype(prim) and self._drawn(prim):
                part = self._mesh(prim, np.asarray(self.xforms.GetLocalToWorldTransform(prim), np.float64),
                                  str(prim.GetPath()))
                if part is not None:
                    parts.append(part)
        for instancer, targets in instancers:
            if not self._drawn(instancer.GetPrim()) or is_prototype(instancer.GetPrim().GetParent()):
                continue
            world = np.asarray(self.xforms.GetLocalToWorldTransform(instancer.GetPrim()), np.float64)
            proto_index, placements = self._instances(instancer)
            for t, target in enumerate(targets):
                root = self.stage.GetPrimAtPath(target)
                if not root:
                    continue
                for prim in Usd.PrimRange(root, Usd.TraverseInstanceProxies()):
                    if not prim.IsA(UsdGeom.Mesh) or not self._drawn(prim, under=root):
                        continue
                    # The mesh in its prototype, the prototype root's own transform included.
                    local, _ = self.xforms.ComputeRelativeTransform(prim, root.GetParent())
                    local = np.asarray(local, np.float64)
                    for k in np.nonzero(proto_index == t)[0]:
                        part = self._mesh(prim, local @ placements[k] @ world, f"{prim.GetPath()}[{k}]")
                        if part is not None:
                            parts.append(part)
        cameras, lights = [], []
        for prim in self.stage.Traverse(Usd.TraverseInstanceProxies()):
            is_camera, is_light = prim.IsA(UsdGeom.Camera), prim.HasAPI(UsdLux.LightAPI)
            if not (is_camera or is_light) or is_prototype(prim) or not self._drawn(prim):
                continue
            if is_camera:
                cameras.append(self._camera(prim, [c.name for c in cameras]))
            elif prim.IsA(UsdLux.CylinderLight):  # an emitting surface: a part of its own
                part = self._cylinder_light(prim)
                if part is not None:
                    parts.append(part)
            else:
                light = self._light(prim)
                if light is not None:
                    lights.append(light)
        return MeshFile(self.path, parts, self.materials, up_axis=self.up, cameras=cameras, lights=lights)

    def _placement(self, prim) -> np.ndarray:
        """The prim's local-to-world transform as column vectors (p' = M p), its translation in metres."""
        m = np.asarray(self.xforms.GetLocalToWorldTransform(prim), np.float64).T.copy()
        m[:3, 3] *= self.meters
        return m

    def _camera(self, prim, taken) -> FileCamera:
        """A UsdGeomCamera: it looks down its -z with +y up; its vertical field of view is
        2 atan(verticalAperture / (2 focalLength)) (both in the same tenths of a unit)."""
        from pxr import UsdGeom

        cam, t = UsdGeom.Camera(prim), self.time
        name = unique_name(prim.GetName(), taken)
        where = str(prim.GetPath())
        focal = float(cam.GetFocalLengthAttr().Get(t))
        vertical = float(cam.GetVerticalApertureAttr().Get(t))
        horizontal = float(cam.GetHorizontalApertureAttr().Get(t))
        if not (focal > 0 and vertical > 0 and horizontal > 0):
            raise SceneError(self.src, f"{where}.focalLength", f"expected a focal length and apertures > 0, got "
                                                               f"{focal:g}, {horizontal:g} x {vertical:g}")
        if cam.GetHorizontalApertureOffsetAttr().Get(t) or cam.GetVerticalApertureOffsetAttr().Get(t):
            warn(self.src, where, "the aperture offset (lens shift) is not read: the view is centred")
        near = float(cam.GetClippingRangeAttr().Get(t)[0]) * self.meters
        authored = cam.GetHorizontalApertureAttr().HasAuthoredValue() or cam.GetVerticalApertureAttr().HasAuthoredValue()
        kind = "orthographic" if cam.GetProjectionAttr().Get(t) == UsdGeom.Tokens.orthographic else "perspective"
        fovy = math.degrees(2.0 * math.atan(vertical / (2.0 * focal)))
        return look_from_matrix(self._placement(prim), name, kind, fovy, near if near > 0 else 1.0,
                                horizontal / vertical if authored else None)

    def _light(self, prim) -> Light | None:
        """A UsdLux light: C_l = intensity x 2^exposure x colour. A RectLight (width x height), a DiskLight
        of radius > 0 (emitting along the prim's -z, as UsdLux defines them) or a SphereLight of radius > 0
        (outwards) is an area light of radiance C_l (over its area with normalize); a sphere light of radius 0
        or treatAsPoint, or a disk of radius 0, a point at its centre;
        distant lights directional along the prim's -z; a ShapingAPI cone on a point a spot (cone:angle the
        cutoff, cone:softness the share of it the profile falls over)."""
        from pxr import UsdLux

        where, t = str(prim.GetPath()), self.time
        api = UsdLux.LightAPI(prim)
        color = np.asarray(api.GetColorAttr().Get(t), np.float64)
        c_l = tuple(float(x) for x in color * float(api.GetIntensityAttr().Get(t)) * 2.0 ** float(api.GetExposureAttr().Get(t)))
        if api.GetEnableColorTemperatureAttr().Get(t):
            warn(self.src, where, "colour temperature is not read; the light's colour is used")
        m = self._placement(prim)
        axis = m[:3, :3] @ [0.0, 0.0, -1.0]
        direction = tuple(float(x) for x in axis / np.linalg.norm(axis))
        name = prim.GetName()
        if prim.IsA(UsdLux.DistantLight):
            return Light(position=None, color=c_l, type="directional", direction=direction, falloff="inverse_square",
                         name=name)
        sized = (prim.IsA(UsdLux.DiskLight) and (UsdLux.DiskLight(prim).GetRadiusAttr().Get(t) or 0) > 0) or (
            prim.IsA(UsdLux.SphereLight) and (UsdLux.SphereLight(prim).GetRadiusAttr().Get(t) or 0) > 0
            and not UsdLux.SphereLight(prim).GetTreatAsPointAttr().Get(t))
        if prim.IsA(UsdLux.RectLight) or sized:
            return self._area_light(prim, m, c_l, name)
        if prim.IsA(UsdLux.DomeLight) or prim.IsA(UsdLux.DomeLight_1):
            return self._dome_light(prim, m, c_l, name)
        if not (prim.IsA(UsdLux.SphereLight) or prim.IsA(UsdLux.DiskLight)):
            warn(self.src, where, f"a {prim.GetTypeName()} is not a Whitted light: skipped")
            return None
        position = tuple(float(x) for x in m[:3, 3])
        shaping = UsdLux.ShapingAPI(prim)
        angle = shaping.GetShapingConeAngleAttr().Get(t) if prim.HasAPI(UsdLux.ShapingAPI) else None
        if angle is None or float(angle) >= 90.0:  # a 90-degree cone (the default) shapes nothing
            return Light(position=position, color=c_l, falloff="inverse_square", name=name)
        softness = min(max(float(shaping.GetShapingConeSoftnessAttr().Get(t) or 0.0), 0.0), 1.0)
        return Light(position=position, color=c_l, type="spot", direction=direction, cutoff_angle=float(angle),
                     beam_width=float(angle) * (1.0 - softness), falloff="inverse_square", name=name)

    def _dome_light(self, prim, m: np.ndarray, c_l: tuple, name: str) -> Light:
        """A DomeLight or DomeLight_1 as an environment light: its latlong texture times C_l, or C_l alone
        without one. UsdLux places the image as OpenEXR's latlong map (pixel (0, 0) at latitude +pi/2,
        longitude +pi; latitude +pi/2 the +y direction, longitude 0 +z, pi/2 +x), which is Mitsuba's envmap
        mapping, warprt's environment's (environment.py), but for where a column's centre sits (OpenEXR
        x / (W - 1) of the turn, Mitsuba (x + 1/2) / W: at most half a texel apart). DomeLight_1's poleAxis
        Z (or "scene" on a Z-up stage) turns that pole from +y to +z (longitude 0 to -y: +90 degrees about
        x) before the prim's world rotation; lights stay in the stage's own space, as the others here do."""
        from pxr import UsdLux

        where, t = str(prim.GetPath()), self.time
        dome = UsdLux.DomeLight_1(prim) if prim.IsA(UsdLux.DomeLight_1) else UsdLux.DomeLight(prim)
        asset, image = dome.GetTextureFileAttr().Get(t), None
        if asset is not None and asset.path:
            layout = str(dome.GetTextureFormatAttr().Get(t))
            if layout not in ("automatic", "latlong"):
                raise SceneError(self.src, f"{where}.inputs:texture:format", f"a {layout} dome texture is not read: "
                                                                             "only latlong (equirectangular) maps")
            path = asset.resolvedPath or str(Path(self.src).parent / asset.path)
            try:
                texture = image_texture(path, source=path)
            except SceneError as e:
                raise SceneError(self.src, f"{where}.inputs:texture:file", str(e)) from None
            image = Texture(image=np.ascontiguousarray(texture.image * np.float32(c_l), np.float32), source=path)
        r, exact = nearest_rotation(m[:3, :3])
        if not exact:
            warn(self.src, where, "the dome's transform is not a rotation: its nearest rotation is read")
        pole = str(dome.GetPoleAxisAttr().Get(t)) if prim.IsA(UsdLux.DomeLight_1) else "Y"  # DomeLight: +y always
        if pole == "scene":
            pole = self.up or "Y"
        if pole == "Z":
            r = r @ _POLE_Z
        return Light(type="environment", image=image, radiance=c_l if image is None else None, rotate=euler_xyz(r),
                     name=name)

    def _cylinder_light(self, prim) -> MeshPart | None:
        """A CylinderLight (UsdLux: length along its x, radius, emitting outwards from its side, not its
        caps) as a tube of CYLINDER_LIGHT_SECTORS quads placed by the prim's transform, with a material of
        its own that emits C_l (over the tube's area with normalize) and reflects nothing: an emissive
        object, an area light over its triangles."""
        from pxr import UsdLux

        where, t = str(prim.GetPath()), self.time
        light = UsdLux.CylinderLight(prim)
        length, radius = float(light.GetLengthAttr().Get(t)), float(light.GetRadiusAttr().Get(t))
        if not (length > 0.0 and radius > 0.0):
            warn(self.src, where, f"a CylinderLight of length {length:g} and radius {radius:g} emits from no surface: skipped")
            return None
        if light.GetTreatAsLineAttr().Get(t):
            warn(self.src, where, f"treatAsLine is not read: the light is a cylinder of radius {radius:g}")
        if prim.HasAPI(UsdLux.ShapingAPI):
            warn(self.src, where, "shaping (a cone) is not read for an area light: it emits over its hemisphere")
        api = UsdLux.LightAPI(prim)
        c_l = np.asarray(api.GetColorAttr().Get(t), np.float64) * float(api.GetIntensityAttr().Get(t)) \
            * 2.0 ** float(api.GetExposureAttr().Get(t))
        if api.GetEnableColorTemperatureAttr().Get(t):
            warn(self.src, where, "colour temperature is not read; the light's colour is used")
        v, f = cylinder(radius, length, CYLINDER_LIGHT_SECTORS)
        n = CYLINDER_LIGHT_SECTORS
        v, f = v[:2 * n], f[:2 * n]  # the side; the caps (and their centres) do not emit
        v = v[:, [1, 0, 2]] * [1.0, -1.0, 1.0]  # along x: a rotation about z (y to x, x to -y), winding kept
        to_world = np.asarray(self.xforms.GetLocalToWorldTransform(prim), np.float64)
        vertices = (v @ to_world[:3, :3] + to_world[3, :3]) * self.meters
        area = 0.5 * float(np.linalg.norm(np.cross(vertices[f[:, 1]] - vertices[f[:, 0]],
                                                   vertices[f[:, 2]] - vertices[f[:, 0]]), axis=1).sum())
        radiance = c_l / (area if api.GetNormalizeAttr().Get(t) else 1.0)
        if not np.any(radiance > 0.0):
            warn(self.src, where, "a black CylinderLight emits nothing: skipped")
            return None
        emitter = Material(kd=(0.0, 0.0, 0.0), ka=(0.0, 0.0, 0.0), ks=(0.0, 0.0, 0.0),
                           emission=tuple(float(x) for x in radiance))
        slot = self._material(f"{where} (light)", f"{prim.GetName()} (light)", lambda: emitter)
        return MeshPart(where, vertices, f, np.full(len(f), slot, np.int64))

    def _area_light(self, prim, m: np.ndarray, c_l: tuple, name: str) -> Light:
        """A RectLight, DiskLight or SphereLight as an area light: its extent placed by the prim's transform
        (in metres), a rectangle or disk emitting along its -z, a sphere outwards; radiance C_l, divided by
        the area where normalize is on."""
        from pxr import UsdLux

        where, t = str(prim.GetPath()), self.time
        api = UsdLux.LightAPI(prim)
        linear = m[:3, :3] * self.meters
        center = tuple(float(x) for x in m[:3, 3])
        if prim.HasAPI(UsdLux.ShapingAPI):
            warn(self.src, where, "shaping (a cone) is not read for an area light: it emits over its hemisphere")
        if prim.IsA(UsdLux.RectLight):
            rect = UsdLux.RectLight(prim)
            width, height = float(rect.GetWidthAttr().Get(t)), float(rect.GetHeightAttr().Get(t))
            if rect.GetTextureFileAttr().Get(t):
                warn(self.src, where, "the light's texture is not read: it emits its colour everywhere")
            # u x v along -z: u the local y half-edge, v the local x one.
            u, v = linear @ [0.0, 0.5 * height, 0.0], linear @ [0.5 * width, 0.0, 0.0]
            area = 4.0 * float(np.linalg.norm(np.cross(u, v)))
            light = dict(shape="rectangle", center=center, u=tuple(map(float, u)), v=tuple(map(float, v)))
        else:
            sphere = prim.IsA(UsdLux.SphereLight)
            radius = float((UsdLux.SphereLight(prim) if sphere else UsdLux.DiskLight(prim)).GetRadiusAttr().Get(t))
            x, y, z = (linear @ e for e in np.eye(3))
            r = radius * float(np.linalg.norm(x))
            uniform = np.isclose(np.linalg.norm(x), np.linalg.norm(y), rtol=1e-6) and abs(np.dot(x, y)) < 1e-6 * np.dot(x, x)
            if sphere:
                uniform = uniform and np.isclose(np.linalg.norm(x), np.linalg.norm(z), rtol=1e-6)
            if not uniform:
                kind = "sphere" if sphere else "disk"
                warn(self.src, where, f"a non-uniformly scaled {kind} light is read as a {kind} of radius {r:g}")
            if sphere:
                area = 4.0 * math.pi * r * r
                light = dict(shape="sphere", center=center, radius=r)
            else:
                normal = -np.cross(x, y)
                area = math.pi * r * r
                light = dict(shape="disk", center=center, normal=tuple(map(float, normal / np.linalg.norm(normal))),
                             radius=r)
        radiance = np.asarray(c_l, np.float64) / (area if api.GetNormalizeAttr().Get(t) else 1.0)
        return Light(type="area", radiance=tuple(map(float, radiance)), name=name, **light)

    def _drawn(self, prim, under=None) -> bool:
        from pxr import UsdGeom

        image = UsdGeom.Imageable(prim)
        if under is None and image.ComputeVisibility(self.time) == UsdGeom.Tokens.invisible:
            return False
        if under is not None and image.GetVisibilityAttr().Get(self.time) == UsdGeom.Tokens.invisible:
            return False
        return image.ComputePurpose() not in (UsdGeom.Tokens.guide, UsdGeom.Tokens.proxy)

    def _instances(self, instancer) -> tuple[np.ndarray, np.ndarray]:
        """Per visible instance: its prototype's index and its transform in the instancer's space (row
        vectors), computed in float64 from normalised quaternions (orientations are half precision, and
        pxr does not normalise them: a scale of 2 would come out 1.9996)."""
        t = self.time
        proto_index = np.asarray(instancer.GetProtoIndicesAttr().Get(t) or [], np.int64)
        n = len(proto_index)
        positions = instancer.GetPositionsAttr().Get(t)
        orientations = instancer.GetOrientationsAttr().Get(t)
        scales = instancer.GetScalesAttr().Get(t)
        m = np.tile(np.eye(4), (n, 1, 1))
        if scales is not None and len(scales) == n:
            m[:, :3, :3] = np.asarray(scales, np.float64)[:, :, None] * np.eye(3)
        if orientations is not None and len(orientations) == n:
            q = np.array([[float(o.GetReal()), *(float(c) for c in o.GetImaginary())] for o in orientations])
            m[:, :3, :3] = m[:, :3, :3] @ _rotation_rows(q / np.linalg.norm(q, axis=1, keepdims=True))
        if positions is not None and len(positions) == n:
            m[:, 3, :3] = np.asarray(positions, np.float64)
        visible = np.ones(n, bool)
        invisible = instancer.GetInvisibleIdsAttr().Get(t)
        if invisible:
            ids = instancer.GetIdsAttr().Get(t)
            ids = np.asarray(ids, np.int64) if ids else np.arange(n)
            visible &= ~np.isin(ids, np.asarray(invisible, np.int64))
        return proto_index[visible], m[visible]

    def _mesh(self, prim, to_world: np.ndarray, name: str) -> MeshPart | None:
        from pxr import UsdGeom, UsdShade

        t = self.time
        mesh = UsdGeom.Mesh(prim)
        points = mesh.GetPointsAttr().Get(t)
        counts = mesh.GetFaceVertexCountsAttr().Get(t)
        indices = mesh.GetFaceVertexIndicesAttr().Get(t)
        if points is None or counts is None or indices is None or len(counts) == 0:
            return None
        points = np.asarray(points, np.float64).reshape(-1, 3)
        counts = np.asarray(counts, np.int64)
        indices = np.asarray(indices, np.int64)
        if counts.sum() != len(indices) or (counts < 0).any():
            raise SceneError(self.src, name, f"faceVertexCounts add up to {counts.sum()} but there are "
                                             f"{len(indices)} faceVertexIndices")
        if len(indices) and (indices.min() < 0 or indices.max() >= len(points)):
            raise SceneError(self.src, name, f"a face refers to a vertex that does not exist (the prim has {len(points)})")
        corner, polygon = fan_corners(counts, mesh.GetHoleIndicesAttr().Get(t) or [])
        position = indices[corner]

        per_polygon = np.full(len(counts), self._bound(prim), np.int64)
        for subset in UsdShade.MaterialBindingAPI(prim).GetMaterialBindSubsets():
            k = self._bound(subset.GetPrim())
            ids = np.asarray(subset.GetIndicesAttr().Get(t) or [], np.int64)
            if k >= 0 and len(ids):
                per_polygon[ids[(ids >= 0) & (ids < len(counts))]] = k

        primvars = UsdGeom.PrimvarsAPI(prim)
        uv_name = next((self.uv_names[k] for k in np.unique(per_polygon) if k >= 0 and self.uv_names[k]), "st")
        uv, uv_key = self._primvar(primvars.GetPrimvar(uv_name), name, corner, polygon, position, 2)
        colors, color_key = self._primvar(mesh.GetDisplayColorPrimvar(), name, corner, polygon, position, 3)
        if colors is not None and len(colors) == 1 and mesh.GetDisplayColorPrimvar().GetInterpolation() == "constant":
            colors = None  # one colour for the whole prim: a material, where nothing else is bound
            if (per_polygon < 0).any():
                kd = tuple(max(0.0, float(x)) for x in mesh.GetDisplayColorPrimvar().Get(t)[0])
                k = self._material(name + ".displayColor", f"{prim.GetName()}.displayColor",
                                   lambda: Material(kd=kd, ka=kd, ks=(0.0, 0.0, 0.0)))
                per_polygon[per_polygon < 0] = k
        normals = self._normals(mesh, primvars, name, corner, polygon, position)

        keys = [position] + [key for a, key in ((uv, uv_key), (colors, color_key)) if a is not None]
        faces, rows = weld_corners(keys, len(points))
        rows = iter(rows)
        a = to_world[:3, :3]
        vertices = (points[next(rows)] @ a + to_world[3, :3]) * self.meters
        part = MeshPart(name, vertices, faces, per_polygon[polygon])
        if uv is not None:
            part.uv = uv[next(rows)]
        if colors is not None:
            part.colors = np.clip(colors[next(rows)], 0.0, None)
        if normals is not None:
            part.normals = unit_rows(normals @ np.linalg.inv(a).T)
        left = mesh.GetOrientationAttr().Get(t) == UsdGeom.Tokens.leftHanded
        if left != (np.linalg.det(a) < 0):  # clockwise front faces, or mirrored by the transform
            part.faces = np.ascontiguousarray(part.faces[:, ::-1])
            part.normals = None if part.normals is None else np.ascontiguousarray(part.normals[:, ::-1])
        return part

    def _primvar(self, pv, name, corner, polygon, position, width):
        """A primvar's values and, per triangle corner, the index of its value there; (None, None) if
        the prim has none or too few values for its interpolation (warned)."""
        if not pv or not pv.HasValue():
            return None, None
        values = pv.ComputeFlattened(self.time)  # primvars:<name>:indices applied
        if values is None or len(values) == 0:
            return None, None
        values = np.asarray(values, np.float64).reshape(len(values), -1)[:, :width]
        interpolation = str(pv.GetInterpolation())
        index = {"constant": np.zeros_like(corner), "uniform": np.repeat(polygon[:, None], 3, 1),
                 "vertex": position, "varying": position, "faceVarying": corner}.get(interpolation)
        if index is None or values.shape[1] != width or (index.size and index.max() >= len(values)):
            warn(self.src, f"{name}: {pv.GetName()}", f"{len(values)} values do not fit interpolation "
                                                     f"'{interpolation}'; not read")
            return None, None
        if interpolation in ("faceVarying", "uniform"):
            values, index = dedupe(values, index)  # else every corner would become its own vertex
        return values, index

    def _normals(self, mesh, primvars, name, corner, polygon, position):
        """The prim's own normals at each triangle corner (M, 3, 3), in its local space, or None."""
        pv = primvars.GetPrimvar("normals")
        if pv and pv.HasValue():
            values, index = self._primvar(pv, name, corner, polygon, position, 3)
        else:
            values = mesh.GetNormalsAttr().Get(self.time)
            if values is None or len(values) == 0:
                return None
            values = np.asarray(values, np.float64).reshape(-1, 3)
            interpolation = str(mesh.GetNormalsInterpolation())
            index = {"constant": np.zeros_like(corner), "uniform": np.repeat(polygon[:, None], 3, 1),
                     "faceVarying": corner}.get(interpolation, position)
            if index.size and index.max() >= len(values):
                warn(self.src, f"{name}: normals", f"{len(values)} values do not fit interpolation '{interpolation}'; "
                                                   "normals are computed instead")
                return None
        return None if values is None else values[index]

    def _material(self, key: str, name: str, make, uv_name: str | None = None) -> int:
        if key not in self._index:
            self._index[key] = len(self.materials)
            self.materials.append((unique_name(name, [n for n, _ in self.materials]), make()))
            self.uv_names.append(uv_name)
        return self._index[key]

    def _bound(self, prim) -> int:
        from pxr import UsdShade

        mat, _ = UsdShade.MaterialBindingAPI(prim).ComputeBoundMaterial()
        if not mat:
            return -1
        key = str(mat.GetPath())
        if key not in self._index:
            phong, uv_name = self._phong(mat)
            return self._material(key, mat.GetPrim().GetName(), lambda: phong, uv_name)
        return self._index[key]

    def _phong(self, mat) -> tuple[Material, str | None]:
        """UsdPreviewSurface's diffuseColor as kd (= ka), a value or a UsdUVTexture; an opacity below 1
        makes a dielectric (dielectric_from_usd); a non-zero emissiveColor value is the material's
        emission (its objects become area lights); and the primvar the texture reads its st from."""
        material, uv_name = self._surface(mat)
        shader = mat.ComputeSurfaceSource()[0]
        if shader and shader.GetIdAttr().Get() == "UsdPreviewSurface" and shader.GetInput("emissiveColor"):
            source = _source(shader.GetInput("emissiveColor"))[0]
            if source is not None:
                warn(self.src, str(mat.GetPath()), f"emissiveColor from a {source.GetIdAttr().Get()} shader is not read")
            else:
                value = _value(shader, "emissiveColor")
                emission = tuple(max(0.0, float(x)) for x in value) if value is not None else (0.0, 0.0, 0.0)
                if max(emission) > 0.0:
                    material = replace(material, emission=emission)
        return material, uv_name

    def _surface(self, mat) -> tuple[Material, str | None]:
        where = str(mat.GetPath())
        shader = mat.ComputeSurfaceSource()[0]
        if not shader or shader.GetIdAttr().Get() != "UsdPreviewSurface":
            return Material(kd=_USD_GREY, ka=_USD_GREY, ks=(0.0, 0.0, 0.0)), None
        glass = dielectric_from_usd(shader)
        value = _value(shader, "opacity")
        if value is not None and float(value) != 1.0 and not glass:
            warn(self.src, where, "transparency (opacity) is not rendered")
        inp = shader.GetInput("diffuseColor")
        source, output, last = _source(inp) if inp else (None, None, None)
        grey = replace(Material(kd=_USD_GREY, ka=_USD_GREY, ks=(0.0, 0.0, 0.0)), **glass)
        if source is None:
            value = last.Get() if last else None
            kd = tuple(max(0.0, float(x)) for x in value) if value is not None else _USD_GREY
            opacity = 1.0 - glass["transmittance"][0] if glass else 1.0
            kd = tuple(x * opacity for x in kd)  # a dielectric's diffuse part is weighted by its opacity
            return replace(Material(kd=kd, ka=kd, ks=(0.0, 0.0, 0.0)), **{**glass, "kd": kd, "ka": kd}), None
        if source.GetIdAttr().Get() != "UsdUVTexture":
            warn(self.src, where, f"diffuseColor comes from a {source.GetIdAttr().Get()} shader, which is not read")
            return grey, None
        texture, uv_name = self._uv_texture(source, output, where)
        if texture is None:
            return grey, None
        white = (1.0 - glass["transmittance"][0],) * 3 if glass else (1.0, 1.0, 1.0)
        return replace(Material(kd=white, ka=white, ks=(0.0, 0.0, 0.0), kd_texture=texture, ka_texture=texture),
                       **{**glass, "kd": white, "ka": white}), uv_name

    def _uv_texture(self, shader, output, where):
        """A UsdUVTexture as a Texture (its scale and bias applied to the texels), and its st primvar."""
        asset = _value(shader, "file")
        if asset is None:
            warn(self.src, where, "UsdUVTexture without a file; the material is untextured")
            return None, None
        path = asset.resolvedPath or str(Path(self.src).parent / asset.path)
        space = str(_value(shader, "sourceColorSpace") or "auto")
        try:
            texture = image_texture(path, srgb={"sRGB": True, "raw": False}.get(space), source=path)
        except SceneError as e:
            warn(self.src, where, f"{e}; the material is untextured")
            return None, None
        wrap = []
        for axis in ("wrapS", "wrapT"):
            mode = str(_value(shader, axis) or "useMetadata")
            if mode not in ("repeat", "clamp", "mirror", "useMetadata"):
                warn(self.src, where, f"texture {axis} '{mode}' is sampled as repeat")
            wrap.append(mode if mode in ("clamp", "mirror") else "repeat")
        if output not in (None, "rgb"):
            warn(self.src, where, f"diffuseColor reads the texture's '{output}' output; its rgb is used")
        scale, bias = _value(shader, "scale"), _value(shader, "bias")
        if scale is not None or bias is not None:
            s = np.asarray(scale if scale is not None else (1, 1, 1, 1), np.float64)[:3]
            b = np.asarray(bias if bias is not None else (0, 0, 0, 0), np.float64)[:3]
            # An affine map per texel commutes with bilinear filtering: applied once, here.
            image = np.ascontiguousarray(np.maximum(texture.image * s + b, 0.0), np.float32)
            texture = Texture(image=image, source=texture.source)
        texture = texture.wrapped(*wrap)
        uv_name = "st"
        st = shader.GetInput("st")
        if st:
            reader, _, _ = _source(st)
            if reader and str(reader.GetIdAttr().Get()).startswith("UsdPrimvarReader"):
                uv_name = str(_value(reader, "varname") or "st")
        return texture, uv_name


def _source(inp):
    """The shader (and its output) an input is connected to, through Material interface inputs; or
    (None, None, the last input) where the chain ends in a value."""
    from pxr import UsdShade

    for _ in range(16):
        if not inp or not inp.HasConnectedSource():
            return None, None, inp
        source, name, kind = inp.GetConnectedSource()
        if kind == UsdShade.AttributeType.Output:
            return UsdShade.Shader(source.GetPrim()), str(name), None
        inp = source.GetInput(name)
    return None, None, inp


def _value(shader, name):
    inp = shader.GetInput(name)
    if not inp:
        return None
    source, _, last = _source(inp)
    return last.Get() if source is None and last else None


def _rotation_rows(q: np.ndarray) -> np.ndarray:
    """Unit quaternions (w, x, y, z) as rotation matrices acting on row vectors (p' = p R)."""
    w, x, y, z = q.T
    return np.stack([
        np.stack([1 - 2 * (y * y + z * z), 2 * (x * y + w * z), 2 * (x * z - w * y)], -1),
        np.stack([2 * (x * y - w * z), 1 - 2 * (x * x + z * z), 2 * (y * z + w * x)], -1),
        np.stack([2 * (x * z + w * y), 2 * (y * z - w * x), 1 - 2 * (x * x + y * y)], -1)], 1)
