"""Headless camera images of a MuJoCo world: rgb, z-depth and entity segmentation.

One OpenGL context per engine, made on the first render and freed by ``close``: EGL when it
works, else OSMesa (``MUJOCO_GL`` names one to use instead). MuJoCo's ``Renderer`` fixes its
backend when ``mujoco`` is first imported, and its depth uses the model's near and far
planes, so the rig drives ``mjr_render`` itself: it imports the backend's ``GLContext``
directly, writes each camera (eye, forward, up, frustum) into the scene, and reads rgb and
depth from one pass (segmentation takes a second, with MuJoCo's id colours). The
``MjrContext`` holds the model's meshes and textures, so it is made again after a compile;
its offscreen buffer grows to the largest image asked.

Only entities' geoms are drawn: while the scene is made, every other geom (parked pool
bodies) is moved to a geom group the scene does not show, and put back after.
"""

from __future__ import annotations

import contextlib
import importlib
import os
import sys
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import mujoco
import numpy as np

from galton.daemon.engines.base import CameraView
from galton.daemon.engines.mujoco.entities import geom_entities
from galton.protocol import OperationFailedError

if TYPE_CHECKING:
    from galton.daemon.engines.mujoco.engine import MujocoEngine

BACKENDS = ("egl", "osmesa")
SHOWN, HIDDEN = 0, 1  # geom groups while a scene is made: entities' and the rest
HEADLIGHT_AMBIENT = 0.4
SCENE_MARGIN = 64  # scene geoms beyond the model's (planes, decor)
_chosen: str | None = None  # the process's OpenGL backend, once one worked


def backend_name() -> str:
    """The backend renders use (or will first try) in this process."""
    return _chosen or _wanted()[0]


def _wanted() -> tuple[str, ...]:
    asked = os.environ.get("MUJOCO_GL", "").strip().lower()
    return (asked,) if asked in BACKENDS else BACKENDS


def _open_context(width: int, height: int) -> Any:
    """A GLContext of the first backend that works; MUJOCO_GL set to it if unset.

    PyOpenGL binds its platform once per process, so a failed EGL can fall back to OSMesa
    only when it failed before PyOpenGL loaded a platform."""
    global _chosen
    failures = []
    for name in (_chosen,) if _chosen else _wanted():
        if name != "egl" and "OpenGL.platform" not in sys.modules:
            os.environ.pop("PYOPENGL_PLATFORM", None)  # a failed EGL try set it
        try:
            module = importlib.import_module(f"mujoco.{name}")
            context = module.GLContext(width, height)
            with context.as_current():
                pass  # it can be made current
        except Exception as exc:  # any failure of a backend: try the next
            failures.append(f"{name}: {exc}")
            continue
        _chosen = name
        os.environ.setdefault("MUJOCO_GL", name)
        return context
    raise OperationFailedError("no headless OpenGL for MuJoCo's renderer ("
                               + "; ".join(failures) + "); set MUJOCO_GL to egl or osmesa")


class CameraRig:
    """The GL context, MuJoCo's render context and scene for one engine's model."""

    def __init__(self) -> None:
        self._gl: Any = None
        self.model: mujoco.MjModel | None = None
        self._con: Any = None
        self._scene: Any = None
        self._option = _scene_option()

    def close(self) -> None:
        if self._gl is not None:
            with self._gl.as_current():
                self._free_context()
            self._gl.free()
            self._gl = None

    def __del__(self) -> None:
        """An engine dropped unclosed: its GL objects must be freed in its own context (in
        another, they would be that context's)."""
        with contextlib.suppress(Exception):  # nothing to be done in a finalizer
            self.close()

    def _free_context(self) -> None:
        if self._con is not None:
            self._con.free()
        self._con = self._scene = self.model = None

    def _ready(self, model: mujoco.MjModel, width: int, height: int) -> None:
        """The render context for this model, its buffer at least this large (current)."""
        if self.model is not model:
            self._free_context()
            self._con = mujoco.MjrContext(model, mujoco.mjtFontScale.mjFONTSCALE_100)
            mujoco.mjr_setBuffer(mujoco.mjtFramebuffer.mjFB_OFFSCREEN, self._con)
            self._con.readDepthMap = mujoco.mjtDepthMap.mjDEPTH_ZEROFAR
            self._scene = mujoco.MjvScene(model, maxgeom=model.ngeom + SCENE_MARGIN)
            self._scene.flags[mujoco.mjtRndFlag.mjRND_SHADOW] = 0
            self._scene.flags[mujoco.mjtRndFlag.mjRND_REFLECTION] = 0
            self.model = model
        if width > self._con.offWidth or height > self._con.offHeight:
            mujoco.mjr_resizeOffscreen(max(width, self._con.offWidth),
                                       max(height, self._con.offHeight), self._con)

    def render(self, model: mujoco.MjModel, data: mujoco.MjData, shown: np.ndarray,
               geom_label: np.ndarray, cameras: Sequence[CameraView]
               ) -> list[dict[str, np.ndarray]]:
        """The images of each camera; ``shown`` marks the geoms drawn, ``geom_label`` maps
        a geom id to its segmentation label."""
        if self._gl is None:
            self._gl = _open_context(max(v.width for v in cameras),
                                     max(v.height for v in cameras))
        images = []
        with self._gl.as_current():  # and no longer after: any thread may render next
            for view in cameras:
                self._ready(model, view.width, view.height)
                self._update_scene(model, data, shown)
                _aim(self._scene, view)
                images.append(self._images(view, geom_label))
        return images

    def _update_scene(self, model: mujoco.MjModel, data: mujoco.MjData,
                      shown: np.ndarray) -> None:
        groups = model.geom_group.copy()
        model.geom_group[:] = np.where(shown, SHOWN, HIDDEN)
        try:
            mujoco.mjv_updateScene(model, data, self._option, None, mujoco.MjvCamera(),
                                   mujoco.mjtCatBit.mjCAT_STATIC | mujoco.mjtCatBit.mjCAT_DYNAMIC,
                                   self._scene)
        finally:
            model.geom_group[:] = groups
        _light(self._scene)

    def _images(self, view: CameraView, geom_label: np.ndarray) -> dict[str, np.ndarray]:
        rect = mujoco.MjrRect(0, 0, view.width, view.height)
        out: dict[str, np.ndarray] = {}
        if "rgb" in view.outputs or "depth" in view.outputs:
            mujoco.mjr_render(rect, self._scene, self._con)
            rgb = np.empty((view.height, view.width, 3), np.uint8)
            raw = np.empty((view.height, view.width), np.float32)
            mujoco.mjr_readPixels(rgb, raw, rect, self._con)
            if "rgb" in view.outputs:
                out["rgb"] = np.ascontiguousarray(rgb[::-1])
            if "depth" in view.outputs:
                out["depth"] = _z_depth(raw[::-1], view.near, view.far)
        if "segmentation" in view.outputs:
            out["segmentation"] = self._segmentation(rect, view, geom_label)
        return out

    def _segmentation(self, rect: Any, view: CameraView, geom_label: np.ndarray
                      ) -> np.ndarray:
        """A pass in MuJoCo's id colours (scene geom index + 1), mapped to labels."""
        flags = self._scene.flags
        flags[mujoco.mjtRndFlag.mjRND_SEGMENT] = flags[mujoco.mjtRndFlag.mjRND_IDCOLOR] = 1
        try:
            mujoco.mjr_render(rect, self._scene, self._con)
        finally:
            flags[mujoco.mjtRndFlag.mjRND_SEGMENT] = flags[mujoco.mjtRndFlag.mjRND_IDCOLOR] = 0
        rgb = np.empty((view.height, view.width, 3), np.uint8)
        mujoco.mjr_readPixels(rgb, None, rect, self._con)
        ids = rgb[::-1].astype(np.int64)
        segid = ids[..., 0] + (ids[..., 1] << 8) + (ids[..., 2] << 16)
        label_of_segid = np.full(self._scene.ngeom + 1, -1, np.int32)
        for geom in self._scene.geoms[:self._scene.ngeom]:
            if geom.objtype == mujoco.mjtObj.mjOBJ_GEOM and geom.segid >= 0:
                label_of_segid[geom.segid + 1] = geom_label[geom.objid]
        labels: np.ndarray = label_of_segid[np.clip(segid, 0, self._scene.ngeom)]
        return labels


def _scene_option() -> mujoco.MjvOption:
    """Only geoms of the SHOWN group: no sites, tendons, actuators, skins or flexes."""
    option = mujoco.MjvOption()
    option.geomgroup[:] = 0
    option.geomgroup[SHOWN] = 1
    for groups in (option.sitegroup, option.tendongroup, option.actuatorgroup,
                   option.flexgroup, option.skingroup):
        groups[:] = 0
    return option


def _light(scene: Any) -> None:
    """A headlight that shows a surface facing the camera in its own rgba: ambient plus
    diffuse make 1, no specular glare (MuJoCo's default lights it at half)."""
    for light in scene.lights[:scene.nlight]:
        if light.headlight:
            light.ambient[:] = HEADLIGHT_AMBIENT
            light.diffuse[:] = 1.0 - HEADLIGHT_AMBIENT
            light.specular[:] = 0.0


def _aim(scene: Any, view: CameraView) -> None:
    """Both of the scene's (stereo) cameras at the view: eye, forward, up, frustum."""
    forward = view.target - view.eye
    forward = forward / np.linalg.norm(forward)
    up = view.up - forward * float(view.up @ forward)
    up = up / np.linalg.norm(up)
    top = view.near * np.tan(np.radians(view.fov_deg) / 2)
    for camera in scene.camera:
        camera.pos[:] = view.eye
        camera.forward[:] = forward
        camera.up[:] = up
        camera.frustum_center = 0.0
        camera.frustum_bottom, camera.frustum_top = -top, top
        camera.frustum_near, camera.frustum_far = view.near, view.far
        camera.orthographic = 0


def _z_depth(raw: np.ndarray, near: float, far: float) -> np.ndarray:
    """Reversed-z buffer (1 at near, 0 at far) to metres along the view axis; inf where
    nothing was drawn within far."""
    raw64 = raw.astype(np.float64)
    depth = far * near / ((far - near) * raw64 + near)
    depth[raw64 <= 0.0] = np.inf
    return depth.astype(np.float32)


def render(engine: MujocoEngine, cameras: Sequence[CameraView]
           ) -> tuple[list[dict[str, np.ndarray]], list[str]]:
    """The cameras' images at the current positions; labels are the entities seen."""
    if not cameras:
        return [], []
    if engine.cameras is None:
        engine.cameras = CameraRig()
    m, d = engine.model, engine.data
    mujoco.mj_kinematics(m, d)  # the data's poses are from before the last step's move
    names, label = geom_entities(m, engine.ids)
    images = engine.cameras.render(m, d, label >= 0, label, cameras)
    seen = np.unique(np.concatenate([im["segmentation"].ravel() for im in images
                                     if "segmentation" in im] or [np.empty(0, np.int32)]))
    seen = seen[seen >= 0]
    compact = np.full(len(names) + 1, -1, np.int32)  # the last entry maps -1 to -1
    compact[seen] = np.arange(len(seen))
    for im in images:
        if "segmentation" in im:
            im["segmentation"] = compact[im["segmentation"]]
    return images, [names[i] for i in seen]
