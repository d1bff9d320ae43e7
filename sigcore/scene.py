"""The scene description: every entity's visual geometry and colour, built once per simulation (``sim.scene``).

Made from the world file (primitive and mesh objects, humans) and the URDFs' ``<visual>`` elements (robots and
URDF objects; :mod:`sigcore.world.visuals`). Each visual is attached to a TF frame:

* a robot's visuals to its link frames, named by the core (:meth:`sigcore.sim.frames.Frames.name`: the URDF's link
  names, prefixed ``<robot>/`` when the world has several robots);
* an object's or a human's to the frame named after the entity (``can_0``), whose pose is
  ``backend.get_pose(entity)``. A URDF object's visuals of every link are expressed in that frame (its root
  link's), composing the joints' ``<origin>`` from the URDF: fixed joints as they are, a movable joint at its zero
  position (the object URDFs sigcore ships have fixed joints only); the world file's ``scale`` scales them.

The ROS 2 side (``/sigcore/scene`` markers) is published by the core from this description
(:mod:`sigcore.sim.description`); the viewer uses the same description. Nothing here imports ROS.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Iterable
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
from lxml import etree

from .backend import Backend
from .geometry import quat_mul, quat_rotate, quat_to_matrix
from .world.models import Entity, Human, Object, Robot, World
from .world.visuals import Visual, mesh_vertex_bounds, origin, urdf_visuals

log = logging.getLogger("sigcore")

HUMAN_COLOR: tuple[float, float, float, float] = (0.9, 0.7, 0.55, 1.0)
"""The colour of a human's capsule and head (the backends paint them alike)."""

_IDENTITY: tuple[float, float, float, float] = (1.0, 0.0, 0.0, 0.0)


def human_dimensions(height: float) -> tuple[float, float, float]:
    """``(body radius, head radius, top of the body capsule)`` [m] of a standing person ``height`` [m] tall.

    The one owner of a human's shape (both backends build it from this). The body capsule stands on the feet
    (z = 0 in the human's frame) and reaches ``top``; the head sphere touches its top and reaches ``height``.
    """
    body, head = 0.09 * height, 0.065 * height
    return body, head, height - 2 * head


@dataclass(frozen=True)
class EntityScene:
    """The visuals of one entity.

    Attributes:
        name: The entity.
        kind: ``robot``, ``object`` or ``human``.
        visuals: Its visuals (an entity whose URDF has no ``<visual>`` has none).
    """

    name: str
    kind: str
    visuals: tuple[Visual, ...]


FrameName = Callable[[str, str], str]
"""``(robot, link) -> TF frame name`` (``Frames.name``)."""


def entity_scene(world: World, entity: Entity, frame: FrameName) -> EntityScene:
    """The visuals of ``entity`` of ``world``; a robot's link frames are named by ``frame``."""
    if isinstance(entity, Robot):
        document = world.urdf(entity.name)
        visuals = tuple(replace(v, frame=frame(entity.name, v.frame))
                        for v in urdf_visuals(document.root, document.path.parent))
        return EntityScene(entity.name, "robot", visuals)
    if isinstance(entity, Human):
        r_body, r_head, top = human_dimensions(entity.height)
        return EntityScene(entity.name, "human", (
            Visual(entity.name, "capsule", (r_body, top - 2 * r_body), (0.0, 0.0, top / 2), _IDENTITY, HUMAN_COLOR),
            Visual(entity.name, "sphere", (r_head,), (0.0, 0.0, top + r_head), _IDENTITY, HUMAN_COLOR)))
    if entity.urdf is not None:
        return EntityScene(entity.name, "object", _urdf_object(world, entity))
    origin_ = (0.0, 0.0, 0.0)
    if entity.mesh is not None:
        mesh = world.resolve(entity.mesh).resolve()
        return EntityScene(entity.name, "object", (Visual(entity.name, "mesh", (entity.scale,) * 3, origin_,
                                                          _IDENTITY, entity.color, mesh),))
    assert entity.shape is not None and entity.size is not None
    return EntityScene(entity.name, "object", (Visual(entity.name, entity.shape, tuple(entity.size), origin_,
                                                      _IDENTITY, entity.color),))


Color = tuple[float, float, float, float]
"""r, g, b, a in [0, 1]."""


def _given_color(entity: Entity) -> Color | None:
    """The world file's ``color`` of a URDF object when the file gives one: it replaces the URDF's colours."""
    return entity.color if isinstance(entity, Object) and "color" in entity.model_fields_set else None


def link_colors(world: World, entity: Entity) -> dict[str, Color]:
    """The colour of each URDF link of a robot or a URDF object of ``world``, as the scene shows it.

    The backends drop the URDFs' ``<visual>`` elements and their cameras render the collision geometry, so they
    paint each link's collision geometry with this colour: the camera, the viewer and ``/sigcore/scene`` then show
    one colour, from this module. It is the world file's ``color`` for an object that gives one, else the colour of
    the link's first ``<visual>``.

    Returns:
        Colour by URDF link name; links with no visual are absent (paint them
        :data:`~sigcore.world.visuals.DEFAULT_COLOR`); empty for shapes, meshes and humans.
    """
    if isinstance(entity, Human) or (isinstance(entity, Object) and entity.urdf is None):
        return {}
    document = world.urdf(entity.name)
    given = _given_color(entity)
    colors: dict[str, Color] = {}
    for v in urdf_visuals(document.root, document.path.parent):
        colors.setdefault(v.frame, given or v.color)
    return colors


def _urdf_object(world: World, obj: Object) -> tuple[Visual, ...]:
    """A URDF object's visuals in its entity frame (the root link's), joints at zero, scaled by ``obj.scale``;
    the world file's ``color`` replaces the URDF's colours when it is given."""
    document = world.urdf(obj.name)
    links = links_in_root(document.root, document.model.root)
    s = obj.scale
    color = _given_color(obj)
    out = []
    for v in urdf_visuals(document.root, document.path.parent):
        pos, quat = links[v.frame]
        xyz = pos + quat_rotate(quat, np.array(v.xyz))
        wxyz = quat_mul(quat, np.array(v.wxyz))
        size = tuple(x * s for x in v.size)
        out.append(Visual(obj.name, v.shape, size, (float(xyz[0] * s), float(xyz[1] * s), float(xyz[2] * s)),
                          (float(wxyz[0]), float(wxyz[1]), float(wxyz[2]), float(wxyz[3])),
                          color or v.color, v.mesh))
    return tuple(out)


def links_in_root(root: etree._Element, root_link: str) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Pose ``(xyz, wxyz)`` of every link in the root link's frame, every joint at its zero position."""
    joints = {}
    for joint in root.findall("joint"):
        parent, child = joint.find("parent"), joint.find("child")
        if parent is not None and child is not None:
            joints[str(child.get("link"))] = (str(parent.get("link")), origin(joint.find("origin")))
    poses: dict[str, tuple[np.ndarray, np.ndarray]] = {root_link: (np.zeros(3), np.array(_IDENTITY))}

    def pose(link: str) -> tuple[np.ndarray, np.ndarray]:
        if link not in poses:  # the names model checked that the joints form one tree
            parent, (xyz, wxyz) = joints[link]
            pp, pq = pose(parent)
            poses[link] = (pp + quat_rotate(pq, np.array(xyz)), quat_mul(pq, np.array(wxyz)))
        return poses[link]

    for link in root.findall("link"):
        pose(str(link.get("name")))
    return poses


def _local_box(visual: Visual) -> tuple[np.ndarray, np.ndarray] | None:
    """``(min, max)`` of ``visual``'s geometry in its own frame [m]; None for a mesh whose vertices cannot be
    read."""
    s = visual.size
    if visual.shape == "box":
        half = np.array(s) / 2
    elif visual.shape == "sphere":
        half = np.full(3, s[0])
    elif visual.shape == "cylinder":
        half = np.array([s[0], s[0], s[1] / 2])
    elif visual.shape == "capsule":
        half = np.array([s[0], s[0], s[1] / 2 + s[0]])
    else:
        assert visual.mesh is not None
        box = mesh_vertex_bounds(visual.mesh)
        if box is None:
            return None
        a, b = np.array(box[0]) * np.array(s), np.array(box[1]) * np.array(s)
        return np.minimum(a, b), np.maximum(a, b)
    return -half, half


_CORNERS = np.array([[(i >> k) & 1 for k in range(3)] for i in range(8)], dtype=float)


def visual_corners(visual: Visual, pos: np.ndarray, quat: np.ndarray) -> np.ndarray | None:
    """The 8 corners (8, 3) [m] of ``visual``'s box in the frame where its own frame has pose ``(pos, quat)``;
    None for a mesh whose vertices cannot be read."""
    box = _local_box(visual)
    if box is None:
        return None
    lo, hi = box
    rotation = quat_to_matrix(quat_mul(quat, np.array(visual.wxyz)))
    offset = pos + quat_rotate(quat, np.array(visual.xyz))
    return (lo + _CORNERS * (hi - lo)) @ rotation.T + offset


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
            if isinstance(e, Robot):
                urdf = world.urdf(e.name).model
                self._parts[e.name] = {frame(e.name, link): (None if link == urdf.root else link)
                                       for link in urdf.links}
        self._unmeasured: set[Path] = set()

    def add(self, world: World, entities: Iterable[Entity], frame: FrameName) -> None:
        """Entities spawned while running (then :meth:`changed`)."""
        for e in entities:
            self.entities[e.name] = entity_scene(world, e, frame)
            if isinstance(e, Robot):
                urdf = world.urdf(e.name).model
                self._parts[e.name] = {frame(e.name, link): (None if link == urdf.root else link)
                                       for link in urdf.links}

    def remove(self, names: Iterable[str]) -> None:
        """Entities deleted while running (then :meth:`changed`)."""
        for name in names:
            self.entities.pop(name, None)
            self._parts.pop(name, None)

    def frame_parts(self, name: str) -> dict[str, str | None]:
        """Every frame of entity ``name`` -> the part whose pose the backend gives for it: a robot's link frames
        (its root link: None), an object's or a human's own frame (None). ``backend.get_pose(name, part)`` is the
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
