"""The scene description: every entity's visual geometry and colour, built once per simulation (``sim.scene``).

Made from the world file (primitive and mesh objects) and the URDFs' ``<visual>`` elements (robots, people's
generated URDFs and URDF objects; :mod:`sigcore.world.visuals`). Each visual is attached to a TF frame:

* a robot's visuals to its link frames, named by the core (:meth:`sigcore.sim.frames.Frames.name`: the URDF's link
  names, prefixed ``<robot>/`` when the world has several robots);
* a person's to its link frames (``head_man_0``; its feet: ``man_0``), named by the core the same way;
* an object's to the frame named after the entity (``can_0``), whose pose is
  ``backend.get_pose(entity)``. A URDF object's visuals of every link are expressed in that frame (its root
  link's), composing the joints' ``<origin>`` from the URDF: fixed joints as they are, a movable joint at its zero
  position (the object URDFs sigcore ships have fixed joints only); the world file's ``scale`` scales them.

The ROS 2 side (``/sigcore/scene`` markers) is published by the core from this description
(:mod:`sigcore.sim.description`); the viewer uses the same description. Nothing here imports ROS.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Iterable
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from .geometry import quat_rotate
from .world.appearance import EntityScene, FrameName, entity_scene, visual_corners
from .world.models import Entity, Human, Robot, World

if TYPE_CHECKING:
    from .backend import Backend

log = logging.getLogger("sigcore")


class Scene:
    """Every entity's visual geometry, and its axis-aligned bounds at the current poses.

    Args:
        world: The world.
        backend: The built backend (poses for :meth:`bounds`).
        frame: Names a robot's link frames (``Frames.name``).
        on_change: Called with the scene after every :meth:`changed` (the simulation's ``scene`` event).

    Attributes:
        entities: Entity name -> its :class:`EntityScene`, in world order. Whoever spawns, deletes or changes an
            entity updates this and calls :meth:`changed`.
        version: Bumped by every :meth:`changed`.
    """

    def __init__(self, world: World, backend: Backend, frame: FrameName,
                 on_change: Callable[[Scene], None] | None = None) -> None:
        self._backend = backend
        self._on_change = on_change
        self.entities: dict[str, EntityScene] = {e.name: entity_scene(world, e, frame) for e in world.entities}
        self.version = 0
        self._parts: dict[str, dict[str, str | None]] = {}
        """entity -> frame -> the part whose pose the backend gives for it (a robot's root link: None)."""
        for e in world.entities:
            if isinstance(e, Robot | Human):
                urdf = world.urdf(e.name).model
                self._parts[e.name] = {frame(e.name, link): (None if link == urdf.root else link)
                                       for link in urdf.links}
        self._unmeasured: set[Path] = set()

    def add(self, world: World, entities: Iterable[Entity], frame: FrameName) -> None:
        """Entities spawned while running (then :meth:`changed`)."""
        for e in entities:
            self.entities[e.name] = entity_scene(world, e, frame)
            if isinstance(e, Robot | Human):
                urdf = world.urdf(e.name).model
                self._parts[e.name] = {frame(e.name, link): (None if link == urdf.root else link)
                                       for link in urdf.links}

    def remove(self, names: Iterable[str]) -> None:
        """Entities deleted while running (then :meth:`changed`)."""
        for name in names:
            self.entities.pop(name, None)
            self._parts.pop(name, None)

    def frame_parts(self, name: str) -> dict[str, str | None]:
        """Every frame of entity ``name`` -> the part whose pose the backend gives for it: a robot's or a person's
        link frames (its root link: None), an object's own frame (None). ``backend.get_pose(name, part)`` is the
        frame's pose in ``world``."""
        return dict(self._parts.get(name, {name: None}))

    def changed(self) -> None:
        """Something was spawned, deleted or changed in :attr:`entities`: bump :attr:`version`, then tell
        ``on_change`` (the simulation emits its ``scene`` event)."""
        self.version += 1
        if self._on_change is not None:
            self._on_change(self)

    def bounds(self, name: str) -> tuple[np.ndarray, np.ndarray]:
        """The axis-aligned box around entity ``name``'s visuals in ``world`` at the current poses [m].

        Each visual's box (a box's corners; a sphere's, cylinder's or capsule's bounding box in its frame; a
        mesh's vertex box, ``.obj`` and ``.stl`` only) is moved by its frame's current world pose from the
        backend. A mesh in another format counts as its origin only (logged once). An entity without visuals is
        the point of its frame's origin.

        Returns:
            ``(min xyz, max xyz)``, each of shape (3,) [m].

        Raises:
            KeyError: no entity ``name``; the message lists the entities.
        """
        entity = self.entities.get(name)
        if entity is None:
            raise KeyError(f"no entity {name!r}; entities: {', '.join(self.entities) or 'none'}")
        parts = self._parts.get(name, {})
        poses: dict[str, tuple[np.ndarray, np.ndarray]] = {}
        points = []
        for visual in entity.visuals:
            if visual.frame not in poses:
                pos, quat = self._backend.get_pose(name, parts.get(visual.frame))
                poses[visual.frame] = (np.asarray(pos, dtype=float), np.asarray(quat, dtype=float))
            pos, quat = poses[visual.frame]
            corners = visual_corners(visual, pos, quat)
            if corners is None:
                if visual.mesh not in self._unmeasured:
                    self._unmeasured.add(visual.mesh)  # type: ignore[arg-type]
                    log.warning("bounds of %s: mesh %s is not .obj or .stl (or unreadable); it counts as its "
                                "origin", name, visual.mesh)
                corners = (pos + quat_rotate(quat, np.array(visual.xyz)))[None, :]
            points.append(corners)
        if not points:
            pos, _ = self._backend.get_pose(name)
            return np.asarray(pos, dtype=float).copy(), np.asarray(pos, dtype=float).copy()
        every = np.vstack(points)
        return every.min(axis=0), every.max(axis=0)
