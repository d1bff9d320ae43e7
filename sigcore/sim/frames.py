"""Frame names and the TF tree of a world: one owner for its names, its fixed part and the computation of the rest.

Frames follow REP-105: with one robot, ``odom`` and the URDF's link names (``base_link``); with several, each robot's
frames are prefixed with ``<robot>/``. Objects are frames named after the entity. A person's frames follow REP-155:
its feet are the frame named after it, each link of its body (:mod:`sigcore.world.body`) is ``<link>_<person>``
(``body_man_0``, ``head_man_0``, ``l_wrist_man_0``). The tree has one root, ``world``:

* a robot's root link: ``world -> odom`` (static, its start pose on the ground) and ``odom -> <root>`` (the wheel
  odometry, ``sim.entities.odometry``, published by the transport) for a robot with a ``<drive>``; ``world -> <root>``
  static at its pose for a ``fixed="true"`` robot; ``world -> <root>`` from the backend's pose (ground truth,
  :meth:`Frames.transforms`) for any other robot;
* every fixed joint: ``parent -> child`` from the URDF's joint ``<origin>`` (static);
* every movable joint: ``parent -> child`` from the joint ``<origin>``, ``<axis>`` and the joint's position, as
  robot_state_publisher computes it (:meth:`Frames.transforms`); floating and planar joints from the backend's
  link poses;
* every person: ``world -> <person>`` from the backend's pose, its fixed joints static, its movable joints from
  the backend's joint angles (:meth:`Frames.transforms`, as a free robot's);
* every object: ``world -> <entity>`` from the backend's pose (:meth:`Frames.entity_transforms`);
* every camera: ``<link> -> <camera>_link`` at the camera's pose and ``<camera>_link -> <camera>_optical_frame``
  (z forward, x right, y down), both static.

A feature may re-parent a robot's ``odom`` (SLAM: ``world -> map`` static, ``map -> odom`` on ``/tf``): each child
frame has exactly one parent here, so the tree keeps one root. The static part is published by the core on
``/tf_static`` (latched) through the publication contract; the rest by a transport (ROS 2: ``/tf``) at its rates.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Literal

import numpy as np

from ..geometry import quat_conj, quat_from_rpy, quat_mul, quat_rotate, quat_yaw
from ..publish import Publication, Publisher, planar_quaternion, transform_fields
from ..world.body import ROOT
from ..world.exceptions import WorldError, WorldIssue
from ..world.urdf import UrdfJoint

if TYPE_CHECKING:
    from .simulation import Simulation

WORLD = "world"
"""The root frame: the world file's frame."""

TF_STATIC = Publication("/tf_static", "tf2_msgs/msg/TFMessage", "latched",
                        "the fixed part of the TF tree: world -> odom per robot with a <drive>, world -> root link "
                        "per fixed robot, every fixed joint")

OPTICAL = (0.5, -0.5, 0.5, -0.5)
"""Rotation (w, x, y, z) from a camera's body frame (x forward, z up) to its optical frame (z forward, x right, y
down; REP-103): roll -π/2, then yaw -π/2."""

Vec3 = tuple[float, float, float]
Quat = tuple[float, float, float, float]
Transform = tuple[str, str, Vec3, Quat]
"""``(parent, child, translation [m], rotation (w, x, y, z))``."""

RootMode = Literal["odom", "fixed", "free"]
"""How a robot's root link hangs in the tree: under ``odom`` (a ``<drive>``), static under ``world``
(``fixed="true"``), or under ``world`` at the backend's pose (any other robot)."""


@dataclass(frozen=True, slots=True)
class _Moving:
    """One transform of a robot computed at each publication: a movable joint, or a pose read from the backend.

    Attributes:
        parent: TF name of the parent frame.
        child: TF name of the child frame.
        kind: ``revolute`` (also continuous), ``prismatic``, or ``pose`` (the child's pose in the parent's, read
            from the backend: a free root, a floating or planar joint).
        index: Position of the joint in the URDF's movable joints (the order of joint_states); -1 for ``pose``.
        origin: The joint ``<origin xyz>`` [m].
        rotation: The joint ``<origin rpy>`` as a quaternion (w, x, y, z).
        axis: Unit axis in the child frame (revolute), or the axis in the parent frame (prismatic).
        links: For ``pose``: the backend parts of parent and child (None: the root link; parent "" is the world).
    """

    parent: str
    child: str
    kind: Literal["revolute", "prismatic", "pose"]
    index: int = -1
    origin: Vec3 = (0.0, 0.0, 0.0)
    rotation: Quat = (1.0, 0.0, 0.0, 0.0)
    axis: Vec3 = (0.0, 0.0, 0.0)
    links: tuple[str | None, str | None] = (None, None)


class Frames:
    """Frame names, the static transforms ``child -> (parent, translation [m], rotation (w, x, y, z))``, and the
    computation of the moving ones.

    Args:
        sim: The simulation (its backend must be built: root poses are read from its initial state).

    Raises:
        WorldError: an object or human is named like a frame of a robot (with one robot: one of its links,
            ``odom`` or ``map``) or ``world``, located at the entity's ``name``.
    """

    def __init__(self, sim: Simulation) -> None:
        self._sim = sim
        robots = [a.name for a in sim.world.agents if a.kind == "robot"]
        self._prefix = {r: (f"{r}/" if len(robots) > 1 else "") for r in robots}
        self._people = [a.name for a in sim.world.agents if a.kind == "human"]
        self._static: dict[str, tuple[str, tuple[float, ...], tuple[float, ...]]] = {}
        self._publisher: Publisher | None = None  # declared once the constructor has filled the tree
        self._mode: dict[str, RootMode] = {}
        self._moving: dict[str, tuple[_Moving, ...]] = {}
        self._entities = tuple(a.name for a in sim.world.agents if a.kind == "object")
        self._check_entity_names(robots)
        for robot in robots:
            self._add_robot(robot)
        for person in self._people:
            self._add_person(person)
        self._publisher = sim.publications.declare(TF_STATIC)
        self.publish()

    def _add_robot(self, robot: str) -> None:
        sim = self._sim
        model = sim.entities.robot_model(robot)
        self._mode[robot] = "fixed" if model.fixed else "odom" if model.drive is not None else "free"
        if self._mode[robot] != "free":
            pos, quat = sim.backend.get_pose(robot)
            if self._mode[robot] == "fixed":
                self.set_static(WORLD, self.name(robot, sim.entities.urdf(robot).root), pos, quat)
            else:
                self.set_static(WORLD, self.name(robot, "odom"), (pos[0], pos[1], 0.0),
                                planar_quaternion(quat_yaw(quat)))
        self._moving[robot] = self._robot_tree(robot)
        for camera in model.cameras:
            self.set_static(self.name(robot, camera.link), self.name(robot, camera.link_frame), camera.pose.xyz,
                            quat_from_rpy(*camera.pose.rpy))
            self.set_static(self.name(robot, camera.link_frame), self.name(robot, camera.optical_frame),
                            (0.0, 0.0, 0.0), OPTICAL)

    def _add_person(self, person: str) -> None:
        self._mode[person] = "free"
        self._moving[person] = self._robot_tree(person)

    # ------------------------------------------------------------------ run-time changes
    def taken(self) -> dict[str, str]:
        """Every frame name in use -> what it is (for refusing an entity that would reuse one)."""
        taken = {WORLD: "the root frame of the TF tree"}
        for robot in self._prefix:
            for link in self._sim.entities.urdf(robot).links:
                taken.setdefault(self.name(robot, link), f"the frame of link '{link}' of robot '{robot}'")
            taken.setdefault(self.name(robot, "odom"), f"the odometry frame of robot '{robot}'")
            taken.setdefault(self.name(robot, "map"), f"the map frame of robot '{robot}' (SLAM)")
            for camera in self._sim.entities.robot_model(robot).cameras:
                for frame in (camera.link_frame, camera.optical_frame):
                    taken.setdefault(self.name(robot, frame), f"a frame of camera '{camera.name}' of robot '{robot}'")
        for person in self._people:
            for link in self._sim.entities.urdf(person).links:
                if link != ROOT:  # the feet frame is the person's name, which is taken as an agent name
                    taken.setdefault(self.name(person, link), f"the frame of link '{link}' of human '{person}'")
        for entity in self._entities:
            taken.setdefault(entity, f"the frame of entity '{entity}'")
        return taken

    def spawn_prefix(self, robot: str) -> str:
        """The prefix a robot spawned now gets: ``""`` when no robot exists, else ``"<robot>/"`` (the frames of
        robots already running are never renamed)."""
        return "" if not self._prefix else f"{robot}/"

    def add(self, entities: Sequence[tuple[str, str]]) -> None:
        """Entities spawned while running, ``(name, kind)``: a robot's tree (prefix :meth:`spawn_prefix`, static
        part republished), an object's or human's frame. The simulation has checked names against
        :meth:`taken`."""
        publisher, self._publisher = self._publisher, None  # publish the static tree once, at the end
        try:
            for name, kind in entities:
                if kind == "robot":
                    self._prefix[name] = self.spawn_prefix(name)
                    self._add_robot(name)
                elif kind == "human":
                    self._people.append(name)
                    self._add_person(name)
                else:
                    self._entities = (*self._entities, name)
        finally:
            self._publisher = publisher
        self._republish()

    def remove(self, names: Sequence[str]) -> None:
        """Entities deleted while running: their frames leave the tree (static part republished)."""
        gone = set(names)
        for robot in [r for r in self._prefix if r in gone]:
            mine = {self.name(robot, link) for link in self._sim.entities.urdf(robot).links} | {
                self.name(robot, "odom"), self.name(robot, "map")} | {
                self.name(robot, frame) for camera in self._sim.entities.robot_model(robot).cameras
                for frame in (camera.link_frame, camera.optical_frame)}
            for child in [c for c in self._static if c in mine]:
                self._static.pop(child)
            del self._prefix[robot]
            self._mode.pop(robot, None)
            self._moving.pop(robot, None)
        for person in [p for p in self._people if p in gone]:
            mine = {self.name(person, link) for link in self._sim.entities.urdf(person).links}
            for child in [c for c in self._static if c in mine]:
                self._static.pop(child)
            self._people.remove(person)
            self._mode.pop(person, None)
            self._moving.pop(person, None)
        self._entities = tuple(e for e in self._entities if e not in gone)
        self._republish()

    def _check_entity_names(self, robots: list[str]) -> None:
        """``WorldError`` at the name of each object or human whose frame name a robot's frame (or another person's
        link frame) already has."""
        taken = {WORLD: "the root frame of the TF tree"}
        for robot in robots:
            for link in self._sim.entities.urdf(robot).links:
                taken.setdefault(self.name(robot, link), f"the frame of link '{link}' of robot '{robot}'")
            taken.setdefault(self.name(robot, "odom"), f"the odometry frame of robot '{robot}'")
            taken.setdefault(self.name(robot, "map"), f"the map frame of robot '{robot}' (SLAM)")
        for person in self._people:
            for link in self._sim.entities.urdf(person).links:
                if link != ROOT:
                    taken.setdefault(self.name(person, link), f"the frame of link '{link}' of human '{person}'")
        world = self._sim.world
        issues = []
        for entity in (*self._entities, *self._people):
            if entity in taken:
                kind = world.agent(entity).kind
                line, column = world.location(entity, "name")
                issues.append(WorldIssue(world.source, line or 1, column or 1, kind, "name",
                                         f"{kind} '{entity}' would be the TF frame '{entity}', which is already "
                                         f"{taken[entity]}; rename the {kind} (each TF frame name is used once)"))
        if issues:
            raise WorldError(issues)

    def _robot_tree(self, robot: str) -> tuple[_Moving, ...]:
        """Put the robot's fixed joints in the static tree; its transforms computed at each publication."""
        urdf = self._sim.entities.urdf(robot)
        index = {j.name: i for i, j in enumerate(urdf.movable_joints)}
        moving: list[_Moving] = []
        if self._mode[robot] == "free":
            moving.append(_Moving(WORLD, self.name(robot, urdf.root), "pose", links=("", None)))
        for joint in urdf.joints:
            parent, child = self.name(robot, joint.parent), self.name(robot, joint.child)
            rotation = _tuple4(quat_from_rpy(*joint.origin_rpy))
            if joint.type == "fixed":
                self.set_static(parent, child, joint.origin_xyz, rotation)
            elif joint.movable:
                moving.append(_joint(joint, parent, child, index[joint.name], rotation))
            else:  # floating, planar: where the backend has the child
                links = (None if joint.parent == urdf.root else joint.parent,
                         None if joint.child == urdf.root else joint.child)
                moving.append(_Moving(parent, child, "pose", links=links))
        return tuple(moving)

    # ------------------------------------------------------------------ names
    def prefix(self, robot: str) -> str:
        """``""`` with one robot, ``"<robot>/"`` with several."""
        return self._prefix[robot]

    def name(self, robot: str, frame: str) -> str:
        """The TF name of ``robot``'s frame ``frame`` (a link, ``odom``, ``map``), or of a person's link (its root,
        the feet: the person's name; any other: ``<link>_<person>``, as REP-155 names a body's frames)."""
        prefix = self._prefix.get(robot)
        if prefix is not None:
            return prefix + frame
        return robot if frame == ROOT else f"{frame}_{robot}"

    @property
    def people(self) -> tuple[str, ...]:
        """The people, whose link transforms :meth:`transforms` computes like a free robot's."""
        return tuple(self._people)

    def root_mode(self, robot: str) -> RootMode:
        """How ``robot``'s root link hangs in the tree (see :data:`RootMode`)."""
        return self._mode[robot]

    # ------------------------------------------------------------------ the moving transforms
    def moving(self, robot: str) -> tuple[tuple[str, str], ...]:
        """``(parent, child)`` of each transform :meth:`transforms` computes for ``robot``, in its order: the root
        link of a free robot (``world -> <root>``), then every non-fixed joint in URDF order. Not ``odom ->
        <root>``: that is the wheel odometry (``sim.entities.odometry``)."""
        return tuple((m.parent, m.child) for m in self._moving[robot])

    def transforms(self, robot: str, positions: Sequence[float] | None = None) -> list[Transform]:
        """The transforms of :meth:`moving` at the current state.

        A revolute or continuous joint rotates its child by the joint position about the axis, a prismatic joint
        translates it along the axis, after the joint ``<origin>`` (as robot_state_publisher does); a free root
        and floating or planar joints take the backend's poses. Plain float arithmetic: about 1 µs per joint.

        Args:
            robot: The robot.
            positions: The positions of the URDF's movable joints in order [rad or m] (as published in
                joint_states); None: read from the backend.
        """
        sim = self._sim
        if positions is None:
            positions = [sim.backend.get_joint_angle(robot, j.name) for j in sim.entities.urdf(robot).movable_joints]
        out: list[Transform] = []
        for m in self._moving[robot]:
            if m.kind == "revolute":
                half = 0.5 * positions[m.index]
                s = math.sin(half)
                ax, ay, az = m.axis
                out.append((m.parent, m.child, m.origin, _qmul(m.rotation, (math.cos(half), ax * s, ay * s, az * s))))
            elif m.kind == "prismatic":
                d = positions[m.index]
                (ox, oy, oz), (ax, ay, az) = m.origin, m.axis
                out.append((m.parent, m.child, (ox + ax * d, oy + ay * d, oz + az * d), m.rotation))
            else:
                out.append(self._relative(robot, m))
        return out

    def _relative(self, robot: str, m: _Moving) -> Transform:
        """The backend's pose of ``m``'s child in its parent (the world for a free root)."""
        backend = self._sim.backend
        cp, cq = backend.get_pose(robot, m.links[1])
        if m.links[0] == "":
            return m.parent, m.child, _tuple3(cp), _tuple4(cq)
        pp, pq = backend.get_pose(robot, m.links[0])
        inv = quat_conj(pq)
        return (m.parent, m.child, _tuple3(quat_rotate(inv, np.asarray(cp) - np.asarray(pp))),
                _tuple4(quat_mul(inv, cq)))

    @property
    def entities(self) -> tuple[str, ...]:
        """The frames of the objects (each named after its entity, child of ``world``)."""
        return self._entities

    def entity_transforms(self) -> list[Transform]:
        """``world -> <entity>`` of every object (:attr:`entities` order) at the backend's pose."""
        get_pose = self._sim.backend.get_pose
        out: list[Transform] = []
        for name in self._entities:
            pos, quat = get_pose(name)
            out.append((WORLD, name, _tuple3(pos), _tuple4(quat)))
        return out

    # ------------------------------------------------------------------ the static tree
    def set_static(self, parent: str, child: str, xyz: Any, wxyz: Any) -> None:
        """Fix ``parent -> child`` (replacing ``child``'s previous parent); republished if already published."""
        self._static[child] = (parent, tuple(float(v) for v in xyz), tuple(float(v) for v in wxyz))
        self._republish()

    def remove_static(self, child: str) -> None:
        """Drop the static transform to ``child`` (another publisher gives it a parent, e.g. on ``/tf``)."""
        if self._static.pop(child, None) is not None:
            self._republish()

    def static(self) -> dict[str, tuple[str, tuple[float, ...], tuple[float, ...]]]:
        """``child -> (parent, xyz, wxyz)`` of every static transform."""
        return dict(self._static)

    def static_fields(self, stamp_ns: int) -> dict[str, Any]:
        """The ``tf2_msgs/TFMessage`` fields of every static transform, stamped ``stamp_ns`` [ns]."""
        return {"transforms": [transform_fields(parent, child, stamp_ns, xyz, wxyz)
                               for child, (parent, xyz, wxyz) in self._static.items()]}

    def publish(self) -> None:
        """Push the static tree on ``/tf_static`` (latched: done at construction and whenever it changes)."""
        assert self._publisher is not None
        self._publisher.publish(self.static_fields(self._sim.stamp_ns()))

    def _republish(self) -> None:
        if self._publisher is not None:
            self.publish()


def _joint(joint: UrdfJoint, parent: str, child: str, index: int, rotation: Quat) -> _Moving:
    """The computation of a movable joint's transform: its origin, and its axis made unit (in the parent frame for
    a prismatic joint, whose child moves along the rotated axis)."""
    axis = np.asarray(joint.axis, dtype=float)
    norm = float(np.linalg.norm(axis))
    axis = axis / norm if norm > 0 else np.zeros(3)  # a zero axis: the joint does not move its child
    if joint.type == "prismatic":
        return _Moving(parent, child, "prismatic", index, joint.origin_xyz, rotation,
                       _tuple3(quat_rotate(np.asarray(rotation), axis)))
    return _Moving(parent, child, "revolute", index, joint.origin_xyz, rotation, _tuple3(axis))


def _qmul(a: Quat, b: Quat) -> Quat:
    """Hamilton product ``a * b`` of (w, x, y, z) tuples (plain floats: a numpy call costs more than this)."""
    aw, ax, ay, az = a
    bw, bx, by, bz = b
    return (aw * bw - ax * bx - ay * by - az * bz, aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx, aw * bz + ax * by - ay * bx + az * bw)


def _tuple3(v: Any) -> Vec3:
    return (float(v[0]), float(v[1]), float(v[2]))


def _tuple4(q: Any) -> Quat:
    return (float(q[0]), float(q[1]), float(q[2]), float(q[3]))
