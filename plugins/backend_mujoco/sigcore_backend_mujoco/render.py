"""Camera images of the MuJoCo world, rendered on a thread of their own.

MuJoCo's OpenGL renderer runs headless through EGL or OSMesa (``MUJOCO_GL``; EGL when unset): on a machine without a
GPU, Debian's Mesa renders in software (llvmpipe); with a GPU, EGL uses it. The renderer keeps its own copy of the
model and its own ``MjData``: a snapshot is the step's ``qpos`` and mocap poses, and the model's body poses (a
static body moved with ``set_pose`` changes the model), copied on the simulation's thread; the render thread computes
the kinematics of that state and draws it, while the simulation steps on. Releasing the interpreter while drawing is
MuJoCo's (``mjr_render`` and ``mjr_readPixels`` run without the GIL).

Each view sets the OpenGL camera itself (position, axes, and a frustum from the intrinsics), so any pose and any
principal point render exactly; depth comes from the depth buffer (reversed-z, MuJoCo's default), converted to
distances along the optical axis.
"""

from __future__ import annotations

import copy
import os
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any, ClassVar

import mujoco
import numpy as np

from sigcore.backend import CameraView, Image, Renderer
from sigcore.errors import BackendError

from .plan import GROUP_COLLISION, GROUP_VISUAL

if TYPE_CHECKING:
    from .backend import MujocoBackend

PACKAGES = "libegl1 libegl-mesa0 libgl1-mesa-dri (EGL) or libosmesa6 (MUJOCO_GL=osmesa)"
"""Debian packages MuJoCo's headless rendering needs on a machine without a GPU driver."""

HEADLIGHT = ((0.5, 0.5, 0.5), (0.5, 0.5, 0.5))
"""Ambient and diffuse light that follows the camera: faces turned to the camera show their colour."""

INFINITE_PLANE = 1000.0
"""Half-size [m] at which the ground plane (infinite for physics) is drawn."""

_SIZES = ("nbody", "ngeom", "nmesh", "ntex", "nmat", "nhfield", "nq", "nmocap", "nlight", "nskin", "nflex")
"""Sizes of a model that decide whether a rendering context made for another model still fits it."""


class MujocoRenderer(Renderer):
    """Renders camera views of a :class:`~sigcore_backend_mujoco.backend.MujocoBackend`'s world (threaded)."""

    threaded: ClassVar[bool] = True

    def __init__(self, backend: MujocoBackend) -> None:
        self._backend = backend
        self._source: mujoco.MjModel | None = None  # the backend's model the copy was made of
        self._model: mujoco.MjModel | None = None
        # on the render thread
        self._ctx: Any = None
        self._gl: Any = None
        self._drawn: mujoco.MjModel | None = None  # the model the context was made for
        self._buffer = (0, 0)

    def snapshot(self) -> object:
        """The step's state: the model copy (a new one after a reset or a spawn), ``qpos``, mocap, body poses."""
        b = self._backend
        model, data = b.model, b.data
        if model is not self._source:
            self._source, self._model = model, copy.copy(model)
        return (self._model, data.qpos.copy(), data.mocap_pos.copy(), data.mocap_quat.copy(), model.body_pos.copy(),
                model.body_quat.copy())

    # ------------------------------------------------------------------ the render thread
    def render(self, snapshot: object, views: Sequence[CameraView]) -> list[tuple[Image | None, Image | None]]:
        assert isinstance(snapshot, tuple)
        model: mujoco.MjModel = snapshot[0]
        qpos, mocap_pos, mocap_quat, body_pos, body_quat = snapshot[1:]
        width = max(v.width for v in views)
        height = max(v.height for v in views)
        try:
            self._prepare(model, width, height)
        except BackendError:
            raise
        except Exception as e:  # MuJoCo's FatalError, EGL's errors: an OpenGL context that does not work here
            raise BackendError(f"MuJoCo cannot render with MUJOCO_GL={os.environ.get('MUJOCO_GL')} ({e}); on "
                               f"Debian install {PACKAGES} (scripts/setup.sh does as root), or set MUJOCO_GL to "
                               "egl, osmesa or glfw") from None
        self._gl.make_current()  # another context may have been current on this thread (cheap when it was ours)
        data, scene, option, free = self._data, self._scene, self._option, self._free
        model.body_pos[:] = body_pos
        model.body_quat[:] = body_quat
        data.qpos[:] = qpos
        data.mocap_pos[:] = mocap_pos
        data.mocap_quat[:] = mocap_quat
        mujoco.mj_kinematics(model, data)
        mujoco.mj_camlight(model, data)
        mujoco.mjv_updateScene(model, data, option, None, free, mujoco.mjtCatBit.mjCAT_ALL, scene)
        out: list[tuple[Image | None, Image | None]] = []
        for view in views:
            out.append(self._draw(scene, view))
        return out

    def _draw(self, scene: mujoco.MjvScene, view: CameraView) -> tuple[Image | None, Image | None]:
        w, h = view.width, view.height
        r = view.rotation  # columns: optical x (right), y (down), z (forward)
        near, far = view.near, view.far
        left, right, bottom, top = view.frustum()
        for cam in (scene.camera[0], scene.camera[1]):
            cam.pos[:] = view.position
            cam.forward[:] = r[:, 2]
            cam.up[:] = -r[:, 1]
            cam.frustum_center = (left + right) / 2
            cam.frustum_width = (right - left) / 2
            cam.frustum_bottom = bottom
            cam.frustum_top = top
            cam.frustum_near = near
            cam.frustum_far = far
            cam.orthographic = 0
        scene.enabletransform = 0
        rect = mujoco.MjrRect(0, 0, w, h)
        mujoco.mjr_render(rect, scene, self._ctx)
        rgb = np.empty((h, w, 3), dtype=np.uint8) if view.rgb else None
        raw = np.empty((h, w), dtype=np.float32) if view.depth else None
        mujoco.mjr_readPixels(rgb, raw, rect, self._ctx)
        depth = None
        if raw is not None:
            d = np.flipud(raw).astype(np.float64)
            # reversed z (1 at near, 0 at far): z = near * far / (near + d * (far - near))
            with np.errstate(divide="ignore"):
                z = near * far / (near + d * (far - near))
            z[d <= 0.0] = np.inf
            depth = z.astype(np.float32)
        return (np.ascontiguousarray(np.flipud(rgb)) if rgb is not None else None), depth

    def _prepare(self, model: mujoco.MjModel, width: int, height: int) -> None:
        """Make (or keep) the OpenGL context, the rendering context and the scene for ``model``: a bigger image than
        the buffer holds makes both contexts anew, at the bigger size (an offscreen buffer outgrowing its OpenGL
        context draws garbage with Mesa's EGL)."""
        bw, bh = max(width, self._buffer[0]), max(height, self._buffer[1])
        if (bw, bh) != self._buffer:
            self.close()
            self._drawn = None
        if self._gl is None:
            self._open_gl(bw, bh)
        fits = self._drawn is not None and all(getattr(model, n) == getattr(self._drawn, n) for n in _SIZES)
        if fits:
            if model is not self._drawn:  # a reset's copy of the same model: the contexts still fit
                _tune(model, bw, bh)
                self._drawn, self._data = model, mujoco.MjData(model)
            return
        _tune(model, bw, bh)
        self._gl.make_current()
        if self._ctx is not None:
            self._ctx.free()
        self._ctx = mujoco.MjrContext(model, mujoco.mjtFontScale.mjFONTSCALE_100)
        mujoco.mjr_setBuffer(mujoco.mjtFramebuffer.mjFB_OFFSCREEN, self._ctx)
        self._ctx.readDepthMap = mujoco.mjtDepthMap.mjDEPTH_ZEROFAR
        self._scene = mujoco.MjvScene(model, maxgeom=max(1000, 4 * model.ngeom))
        self._scene.flags[mujoco.mjtRndFlag.mjRND_SHADOW] = 0  # no shadow acne, and a third less work in software
        self._scene.flags[mujoco.mjtRndFlag.mjRND_REFLECTION] = 0
        self._option = mujoco.MjvOption()
        self._option.geomgroup[:] = 0
        self._option.geomgroup[GROUP_COLLISION] = 1
        self._option.geomgroup[GROUP_VISUAL] = 1
        self._free = mujoco.MjvCamera()
        self._data = mujoco.MjData(model)
        self._drawn, self._buffer = model, (bw, bh)

    def _open_gl(self, width: int, height: int) -> None:
        backend = os.environ.setdefault("MUJOCO_GL", "egl")
        try:
            if backend == "osmesa":
                from mujoco.osmesa import GLContext
            elif backend == "glfw":
                from mujoco.glfw import GLContext  # type: ignore[no-redef]
            else:
                from mujoco.egl import GLContext  # type: ignore[no-redef]
            self._gl = GLContext(width, height)
            self._gl.make_current()
        except Exception as e:  # ImportError, OSError, RuntimeError, EGL's own errors: all mean no OpenGL here
            raise BackendError(f"MuJoCo cannot open an OpenGL context with MUJOCO_GL={backend} ({e}); on Debian "
                               f"install {PACKAGES} (scripts/setup.sh does as root), or set MUJOCO_GL to egl, "
                               "osmesa or glfw") from None

    def close(self) -> None:
        """Free the rendering and OpenGL contexts (on the render thread)."""
        if self._ctx is not None:
            self._gl.make_current()
            self._ctx.free()
            self._ctx = None
        if self._gl is not None:
            self._gl.free()
            self._gl = None
        self._buffer = (0, 0)


def _tune(model: mujoco.MjModel, width: int, height: int) -> None:
    """Set the renderer's copy of a model up for cameras: the offscreen buffer's size, no multisampling (exact edges,
    and the software renderer is faster), the ground plane drawn far, the headlight."""
    model.vis.global_.offwidth, model.vis.global_.offheight = width, height
    model.vis.quality.offsamples = 0
    for g in np.flatnonzero((model.geom_type == mujoco.mjtGeom.mjGEOM_PLANE) & (model.geom_size[:, 0] == 0)):
        model.geom_size[g, :2] = INFINITE_PLANE  # MuJoCo draws an infinite plane only a few metres wide
    model.vis.headlight.ambient[:] = HEADLIGHT[0]
    model.vis.headlight.diffuse[:] = HEADLIGHT[1]
