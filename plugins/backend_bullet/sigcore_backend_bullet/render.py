"""Camera images of the PyBullet world through its CPU renderer (TinyRenderer, ``getCameraImage``).

PyBullet holds the interpreter while it renders and its client is not thread-safe, so this renderer is not threaded:
an image is drawn on the simulation's thread at the step it belongs to (the snapshot is the client itself). Each view
gives TinyRenderer an OpenGL view matrix from the optical frame and a projection matrix from the intrinsics (any
principal point); depth is the depth buffer converted to distances along the optical axis.

Bodies built without a visual shape (sigcore's objects) are drawn from their collision shapes, and the URDFs'
visuals (robots', persons' generated ones) are dropped (:mod:`.urdf_prep`); each link is given its colour in the
scene description once, before the first image (:func:`sigcore.world.appearance.link_colors`; a shape its
world-file colour), so the camera shows what the viewer shows. A person whose body is built again (see
:mod:`.base`) is painted again.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, ClassVar

import numpy as np
import pybullet as pb

from sigcore.backend import CameraView, Image, Renderer
from sigcore.world.appearance import link_colors
from sigcore.world.models import Human, Object, Robot
from sigcore.world.visuals import DEFAULT_COLOR

if TYPE_CHECKING:
    from .backend import BulletBackend

LIGHT = {"lightDirection": [-3.0, -2.0, 10.0], "lightAmbientCoeff": 0.5, "lightDiffuseCoeff": 0.5,
         "lightSpecularCoeff": 0.0, "shadow": 0}
"""TinyRenderer's light: from above, like MuJoCo's sun, with as much ambient light (no shadows)."""


def projection(view: CameraView) -> list[float]:
    """The OpenGL projection matrix (column-major) of ``view``'s intrinsics (``glFrustum`` of
    :meth:`~sigcore.backend.CameraView.frustum`)."""
    n, f = view.near, view.far
    left, right, bottom, top = view.frustum()
    return [2 * n / (right - left), 0.0, 0.0, 0.0,
            0.0, 2 * n / (top - bottom), 0.0, 0.0,
            (right + left) / (right - left), (top + bottom) / (top - bottom), -(f + n) / (f - n), -1.0,
            0.0, 0.0, -2 * f * n / (f - n), 0.0]


class BulletRenderer(Renderer):
    """Renders camera views of a :class:`~sigcore_backend_bullet.backend.BulletBackend`'s world (not threaded)."""

    threaded: ClassVar[bool] = False

    def __init__(self, backend: BulletBackend) -> None:
        self._backend = backend
        self._coloured: dict[str, tuple[int, int]] = {}
        """The entities painted, with the backend's build and the body painted (a reset may build the world again,
        a person's body is replaced when it changes)."""

    def snapshot(self) -> object:
        """Nothing to copy: :meth:`render` is called at once, on the simulation's thread."""
        self._colour()
        return None

    def _colour(self) -> None:
        """Give each object's shape its world-file colour, and each link of a URDF its scene colour (once per
        body)."""
        b = self._backend
        for agent in b._world.agents:  # the renderer is the backend's own: its world and bodies are read here
            if not isinstance(agent, Object | Robot | Human):
                continue
            body = b._entity(agent.name).body
            if self._coloured.get(agent.name) == (b._builds, body):
                continue
            if isinstance(agent, Object) and agent.urdf is None:
                pb.changeVisualShape(body, -1, rgbaColor=list(agent.color), physicsClientId=b.client)
            else:
                colors = link_colors(b._world, agent)
                links = {-1: pb.getBodyInfo(body, physicsClientId=b.client)[0].decode()}
                for i in range(pb.getNumJoints(body, physicsClientId=b.client)):
                    links[i] = pb.getJointInfo(body, i, physicsClientId=b.client)[12].decode()
                for index, link in links.items():
                    pb.changeVisualShape(body, index, rgbaColor=list(colors.get(link, DEFAULT_COLOR)),
                                         physicsClientId=b.client)
            self._coloured[agent.name] = (b._builds, body)

    def render(self, snapshot: object, views: Sequence[CameraView]) -> list[tuple[Image | None, Image | None]]:
        out: list[tuple[Image | None, Image | None]] = []
        for view in views:
            eye = np.asarray(view.position, dtype=float)
            r = view.rotation
            matrix = pb.computeViewMatrix(eye.tolist(), (eye + r[:, 2]).tolist(), (-r[:, 1]).tolist())
            _, _, rgba, buffer, _ = pb.getCameraImage(view.width, view.height, matrix, projection(view),
                                                      renderer=pb.ER_TINY_RENDERER, **LIGHT,
                                                      flags=pb.ER_NO_SEGMENTATION_MASK,
                                                      physicsClientId=self._backend.client)
            shape = (view.height, view.width)
            rgb = np.ascontiguousarray(np.reshape(rgba, (*shape, 4))[..., :3], dtype=np.uint8) if view.rgb else None
            depth = None
            if view.depth:
                d = np.reshape(np.asarray(buffer, dtype=np.float64), shape)
                n, f = view.near, view.far
                z = f * n / (f - (f - n) * d)
                z[d >= 1.0 - 1e-7] = np.inf
                depth = z.astype(np.float32)
            out.append((rgb, depth))
        return out
