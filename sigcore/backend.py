"""The physics backend interface that engine plugins implement (MuJoCo, PyBullet, ...).

Conventions, for every method:

* SI units, world frame z up; quaternions are ``(w, x, y, z)``; vectors are ``numpy`` float arrays of shape (3,).
* Entities are the world's robots, objects and humans, by name. Parts are rigid bodies of an entity: a robot's URDF
  link names, a person's links (its generated URDF, :mod:`sigcore.world.body`: root ``"main"`` at the feet, then
  REP-155's ``body``, ``head``, ``l_wrist``, ...); an object has the single part ``"main"``. ``part=None`` means
  the entity's main part (a robot's root link, a person's feet).
* Joints are a robot's or a person's movable (1-DoF) URDF joints, by name. A person's joints have no motor: they
  stay where ``set_joint_angle`` puts them (target, velocity and torque commands are refused); a static person
  (the default) is held whole, a dynamic one has a free root and held joints (a mannequin).
* The core validates names and values before calling; a backend may assume names exist and numbers are finite.
* Nothing here advances time except :meth:`Backend.step`. The core owns the simulation clock.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Callable, Collection, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, ClassVar, TypeVar

import numpy as np
import numpy.typing as npt

from .errors import BackendError, BackendRefusal
from .world.models import World

if TYPE_CHECKING:
    from .world.urdf import UrdfDocument

Array = npt.NDArray[np.float64]

GROUND = "ground"
"""Entity name reported in contacts with the ground plane (not an agent: it has no API)."""

MAIN = "main"
"""Name of the single part of objects and humans; also accepted for a robot's root link."""


T = TypeVar("T")


def collision_urdf(urdf: UrdfDocument, what: str,
                   check: Callable[[Path], str | None] | None = None) -> tuple[Any, list[str]]:
    """A copy of ``urdf`` as an engine loads it (``urdf`` is not changed): comments and ``<visual>`` elements removed,
    every mesh's file name made absolute; and its root links (those no joint has as child).

    Args:
        urdf: The URDF document (``World.urdf``).
        what: The entity it belongs to, for messages, e.g. ``"robot 'robot_000'"``.
        check: Says what is wrong with a mesh file the engine would choke on (None: nothing).

    Raises:
        BackendError: a collision mesh not found, or one ``check`` finds wrong, or a root link called ``world``.
    """
    from lxml import etree

    from .world.urdf import resolve_mesh

    path = urdf.path
    root = urdf.copy_root()
    etree.strip_tags(root, etree.Comment)
    for visual in list(root.iter("visual")):
        visual.getparent().remove(visual)
    for mesh in root.iter("mesh"):
        filename = str(mesh.get("filename", ""))
        resolved = resolve_mesh(filename, path.parent)
        link = next((a.get("name") for a in mesh.iterancestors("link")), "?")
        if resolved is None:
            raise BackendError(f"{what}: collision mesh '{filename}' of link '{link}' in {path} not found "
                               f"(relative paths are relative to the URDF's directory {path.parent})")
        problem = check(resolved) if check is not None else None
        if problem is not None:
            raise BackendError(f"{what}: collision mesh '{filename}' of link '{link}' in {path}: {problem}")
        mesh.set("filename", str(resolved))
    children = {str(c.get("link")) for c in root.iter("child")}
    roots = [name for name in (str(e.get("name")) for e in root.findall("link")) if name not in children]
    if roots == ["world"]:
        raise BackendError(f"{what}: the root link of {path} is 'world'; remove the 'world' link and its "
                           "joint, and set fixed=\"true\" on the <robot> to weld the robot to the world")
    return root, roots


def entity_urdf(world: World, entity: str, what: str, tree: bool = True) -> UrdfDocument:
    """The world's shared URDF of ``entity`` (a robot, a person, a URDF object), its link and joint tree checked
    too when ``tree``.

    Raises:
        BackendError: the file cannot be read, or (``tree``) its links and joints are not one tree; the message
            starts with ``what`` (the entity, e.g. ``"robot 'robot_000'"``).
    """
    from .world.exceptions import UrdfError

    try:
        document = world.urdf(entity)
        if tree:
            document.model  # noqa: B018 - parsed and checked now, so that a bad tree names the entity
    except UrdfError as e:
        raise BackendError(f"{what}: {e}") from None
    return document


def passive_joint(entity: str, joint: str) -> str:
    """The refusal of a motor command (target, velocity, torque) to a person's joint, which has no motor."""
    return (f"joint '{joint}' of human '{entity}' has no motor: a person's joints are moved kinematically, by "
            "set_joint_angle (or by its motion: a gait, a skeleton stream)")


def find_entity(entities: Mapping[str, T], name: str) -> T:
    """The backend's index of entity ``name``.

    Raises:
        BackendRefusal: no such entity; the message lists them.
    """
    entity = entities.get(name)
    if entity is None:
        raise BackendRefusal(f"no entity '{name}'; entities: {', '.join(entities) or 'none'}")
    return entity


def find_part(kind: str, entity: str, index: Mapping[str, T], part: str, parts: Sequence[str]) -> T:
    """The backend's index of part ``part`` of ``entity`` (a ``kind``) in ``index`` (part name -> index); ``parts``
    are its part names, main part first.

    Raises:
        BackendRefusal: no such part; the message lists the valid ones (and ``main``, which a robot's root also
            answers to).
    """
    found = index.get(part)
    if found is None:
        alias = f" (or '{MAIN}')" if kind == "robot" else ""
        raise BackendRefusal(f"{kind} '{entity}' has no part '{part}'; parts: {', '.join(parts)}{alias}")
    return found


def find_joint(kind: str, entity: str, joints: Mapping[str, T], name: str) -> T:
    """The backend's index of the movable joint ``name`` of ``entity``.

    Raises:
        BackendRefusal: no such joint; the message lists the valid ones.
    """
    joint = joints.get(name)
    if joint is None:
        raise BackendRefusal(f"{kind} '{entity}' has no movable joint '{name}'; joints: {', '.join(joints) or 'none'}")
    return joint


class Backend(ABC):
    """A physics engine holding one world."""

    name: ClassVar[str]
    """Registry name, e.g. ``"mujoco"``."""
    title: ClassVar[str] = ""
    """The engine's name in messages (``MuJoCo``); default: :attr:`name`."""
    _built: bool = False
    """Whether :meth:`build` made a world (a backend sets it)."""
    replay_tolerance: ClassVar[float] = 1e-6
    """How far a replay's poses may be from the recorded ones [m, and unit quaternion components] (``sigcore
    replay``): 0.0 for an engine that is deterministic to the bit on one machine; a backend states its own."""

    # ------------------------------------------------------------------ life cycle
    def require_world(self) -> None:
        """Refuse a call before :meth:`build` made a world.

        Raises:
            BackendError: naming the backend and what to call first.
        """
        if not self._built:
            raise BackendError(f"the {self.title or self.name} backend has no world yet; call build(world) first")

    @abstractmethod
    def build(self, world: World) -> None:
        """Create the engine's model of ``world`` (paths in it are relative to ``world.base_dir``).

        Raises:
            BackendError: the world cannot be built (e.g. a URDF the engine rejects); the message names the entity.
        """

    def close(self) -> None:  # noqa: B027 - optional, nothing to free by default
        """Free the engine's resources (the world is unloaded and this backend is not used again); default:
        nothing."""

    @abstractmethod
    def step(self) -> None:
        """Advance physics by one ``world.timestep``; then clear wrenches and torques applied for this step."""

    batches: bool = False
    """Whether :meth:`step_batch` can take more than one step (the core then counts the steps it may take at once;
    otherwise it does not spend the time)."""

    def step_batch(self, n: int, contacts: bool) -> int:
        """Take up to ``n`` steps (at least one) without coming back to the core, as ``n`` calls of :meth:`step`
        would; return how many were taken. The core calls it when nothing is due before the ``n``-th step.

        Args:
            n: The most steps to take.
            contacts: Someone follows contacts: stop after the first step whose contacts differ from those before
                the call (:meth:`contacts` is then read at that step; the steps in between had the same ones).

        Default: one :meth:`step` (MuJoCo takes many in a compiled loop).
        """
        self.step()
        return 1

    @abstractmethod
    def reset(self) -> None:
        """Restore every body and joint to its state right after :meth:`build`; release all grasps; restore
        gravity, dynamics and collision modes and masses. Time is the core's business and is not touched."""

    # ------------------------------------------------------------------ run-time changes
    def add_entities(self, world: World, names: Sequence[str]) -> None:
        """Add the entities ``names`` of ``world`` to the running world, in one go (MuJoCo: one recompile).

        ``world`` is the running world with them appended to ``world.agents`` (the core has validated them: names
        unique, files readable); every other entity is as before. After the call:

        * every existing body and joint has exactly the state it had (positions, velocities, actuator and servo
          states, held entities, grasps, gravity/dynamics/collision modes, masses, moved static objects);
        * each new entity stands at its model ``pose`` at rest, its joints at 0 held by their servos (its drive
          wheels braked), with welds to every gripper that may grasp it (and its grippers' welds to graspable
          objects) as :meth:`build` makes them;
        * :meth:`parts`, :meth:`joints`, :meth:`contacts`, :meth:`part_of` and :meth:`ray_cast` include it;
          part ids may be renumbered (the core reads :meth:`contacts` afresh);
        * :meth:`reset` restores it to this state (as added).

        Raises:
            BackendError: an entity cannot be built (naming it); the running world is then unchanged. The default
                implementation refuses: a backend that cannot add entities while running.
        """
        raise BackendRefusal(f"backend '{self.name}' cannot add entities to a running world")

    def remove_entities(self, world: World, names: Sequence[str]) -> None:
        """Remove the entities ``names`` from the running world (``world``: the world without them).

        The core has released every grasp that involves them (:meth:`detach`). Every other body keeps its state;
        those that rested on a removed entity fall. :meth:`parts` & co. no longer know the removed names, and
        :meth:`reset` no longer restores them.

        Raises:
            BackendError: the backend cannot remove them (the default implementation refuses).
        """
        raise BackendRefusal(f"backend '{self.name}' cannot remove entities from a running world")

    # ------------------------------------------------------------------ introspection
    @abstractmethod
    def parts(self, entity: str) -> list[str]:
        """Part names of ``entity`` (main part first)."""

    @abstractmethod
    def joints(self, entity: str) -> list[str]:
        """Movable joint names of ``entity`` (empty for objects and humans)."""

    # ------------------------------------------------------------------ state
    @abstractmethod
    def get_pose(self, entity: str, part: str | None = None) -> tuple[Array, Array]:
        """World position [m] and orientation (w, x, y, z) of a part's frame (URDF link frame)."""

    def get_poses(self, parts: Sequence[tuple[str, str | None]]) -> Array:
        """The poses of many parts at once: an (n, 7) array, row i the position [m] and the orientation (w, x, y, z)
        of ``parts[i]`` = ``(entity, part)`` as :meth:`get_pose` gives it. A viewer or a recorder reads every frame
        with one call; a backend may do it faster than one call per part (the default is that loop).

        Raises:
            BackendRefusal: an entity or a part that does not exist (named, like :meth:`get_pose`).
        """
        out = np.empty((len(parts), 7))
        for i, (entity, part) in enumerate(parts):
            pos, quat = self.get_pose(entity, part)
            out[i, :3] = pos
            out[i, 3:] = quat
        return out

    @abstractmethod
    def set_pose(self, entity: str, position: Array | None = None, quaternion: Array | None = None) -> None:
        """Teleport the entity so that its main part has this pose (``None`` keeps that component)."""

    @abstractmethod
    def get_velocity(self, entity: str, part: str | None = None) -> tuple[Array, Array]:
        """Linear [m/s] and angular [rad/s] velocity of a part's frame origin, world frame."""

    @abstractmethod
    def set_velocity(self, entity: str, linear: Array | None = None, angular: Array | None = None) -> None:
        """Set the main part's linear [m/s] / angular [rad/s] velocity, world frame (``None`` keeps it)."""

    @abstractmethod
    def get_com(self, entity: str, part: str | None = None) -> Array:
        """World position [m] of a part's centre of mass."""

    @abstractmethod
    def apply_wrench(self, entity: str, part: str | None, force: Array, torque: Array) -> None:
        """Add a force [N] at the part's centre of mass and a torque [N m], world frame, for the next step only."""

    # ------------------------------------------------------------------ properties and modes
    @abstractmethod
    def get_mass(self, entity: str) -> float:
        """Total mass [kg] of the entity."""

    @abstractmethod
    def set_mass(self, entity: str, mass: float) -> None:
        """Set the total mass [kg] (> 0); every part's mass and inertia are scaled by the same factor."""

    @abstractmethod
    def set_gravity_mode(self, entity: str, enabled: bool) -> None:
        """Whether gravity acts on the entity."""

    @abstractmethod
    def set_dynamics_mode(self, entity: str, enabled: bool) -> None:
        """Dynamics off: the entity is held exactly where it is (kinematic) and moves only through ``set_pose``
        and ``set_joint_angle``; forces have no effect. Dynamics on: simulated normally."""

    @abstractmethod
    def set_collision_mode(self, entity: str, enabled: bool) -> None:
        """Whether the entity collides with anything."""

    # ------------------------------------------------------------------ joints
    @abstractmethod
    def get_joint_angle(self, entity: str, joint: str) -> float:
        """Joint position [rad] or [m]."""

    @abstractmethod
    def set_joint_angle(self, entity: str, joint: str, angle: float) -> None:
        """Set a joint position instantly (kinematic); its position servo then holds that angle."""

    def set_joint_angles(self, entity: str, angles: Mapping[str, float]) -> None:
        """:meth:`set_joint_angle` of every ``joint: angle`` in ``angles`` (a person's posture at one step); a
        backend may do it in one go."""
        for joint, angle in angles.items():
            self.set_joint_angle(entity, joint, angle)

    @abstractmethod
    def get_joint_velocity(self, entity: str, joint: str) -> float:
        """Joint velocity [rad/s] or [m/s]."""

    @abstractmethod
    def set_joint_target(self, entity: str, joint: str, angle: float) -> None:
        """Drive the joint's actuator to a position [rad] (position servo with the world's gains)."""

    @abstractmethod
    def set_joint_velocity(self, entity: str, joint: str, velocity: float, max_torque: float | None = None) -> None:
        """Drive the joint's actuator at a velocity [rad/s] (velocity servo), optionally limiting its torque [N m].
        Wheel joints of a differential drive are always in this mode."""

    @abstractmethod
    def add_joint_torque(self, entity: str, joint: str, torque: float) -> None:
        """Add a torque [N m] (or force [N]) on a joint for the next step only."""

    @abstractmethod
    def get_joint_position(self, entity: str, joint: str) -> Array:
        """World position [m] of the joint's anchor (the child link frame origin)."""

    # ------------------------------------------------------------------ grasping
    @abstractmethod
    def attach(self, entity: str, part: str, obj: str) -> None:
        """Rigidly attach object ``obj`` to ``entity``'s ``part`` in their current relative pose (the core has
        checked the grasp rules)."""

    @abstractmethod
    def detach(self, entity: str, part: str, obj: str) -> None:
        """Remove the attachment made by :meth:`attach`."""

    # ------------------------------------------------------------------ contacts and rays
    @abstractmethod
    def contacts(self) -> frozenset[tuple[int, int]]:
        """Pairs of part ids in contact after the last step, each pair ``(low id, high id)``."""

    @abstractmethod
    def part_of(self, part_id: int) -> tuple[str, str]:
        """``(entity, part)`` of a part id from :meth:`contacts` (``(GROUND, MAIN)`` for the ground plane)."""

    @abstractmethod
    def ray_cast(self, origin: Array, directions: npt.NDArray[np.float64], max_range: float,
                 exclude: str | None = None) -> Array:
        """Cast rays from one origin.

        Args:
            origin: (3,) world point [m].
            directions: (N, 3) unit vectors, world frame.
            max_range: ignore hits further than this [m].
            exclude: an entity whose parts the rays pass through (the sensor's own robot).

        Returns:
            (N,) distances [m]; ``inf`` where nothing is hit within ``max_range``.
        """

    def ray_hits(self, origin: Array, directions: npt.NDArray[np.float64], max_range: float,
                 among: Collection[str]) -> tuple[Array, list[str | None]]:
        """Cast rays that see only the entities ``among`` (they pass through every other entity and the floor):
        where each first hits one, and which (a person's path is checked so against the static entities).

        Args:
            origin: (3,) world point [m].
            directions: (N, 3) unit vectors, world frame.
            max_range: ignore hits further than this [m].
            among: the entities the rays can hit.

        Returns:
            (N,) distances [m] (``inf``: no hit within ``max_range``) and the entity each ray hit (None: none).

        Raises:
            BackendError: the backend cannot tell what a ray hit (the default).
        """
        raise BackendError(f"the {self.name} backend cannot tell which entity a ray hits; backends that can: "
                           "mujoco, bullet")

    # ------------------------------------------------------------------ cameras (optional)
    def renderer(self) -> Renderer:
        """A renderer of this backend's world for cameras (created once per backend and kept by the caller).

        Raises:
            BackendError: the backend cannot render (the default), or its renderer cannot start (no OpenGL: the
                message names the system packages to install).
        """
        raise BackendError(f"the {self.name} backend cannot render camera images; backends that can: mujoco, "
                           "bullet")


@dataclass(frozen=True)
class CameraView:
    """One pinhole view to render, in the world frame.

    Attributes:
        position: (3,) the optical centre [m].
        rotation: (3, 3) the optical frame's axes as columns (REP-103 optical: x right, y down, z forward).
        width: Image width [px].
        height: Image height [px].
        focal: Focal length [px] (square pixels).
        cx: Principal point, column [px] (pixel centres at integers).
        cy: Principal point, row [px].
        near: Nearest rendered distance along z [m].
        far: Farthest rendered distance along z [m].
        rgb: Whether to return colours.
        depth: Whether to return depth.
    """

    position: Array
    rotation: Array
    width: int
    height: int
    focal: float
    cx: float
    cy: float
    near: float
    far: float
    rgb: bool = True
    depth: bool = True

    def frustum(self) -> tuple[float, float, float, float]:
        """``(left, right, bottom, top)`` of the view at the near plane [m], as OpenGL's ``glFrustum`` takes them,
        in the camera's OpenGL frame (y up): the image plane spans pixel edges -0.5 .. width - 0.5 (pixel centres at
        integers, as CameraInfo's K has them)."""
        n, f = self.near, self.focal
        return ((-0.5 - self.cx) / f * n, (self.width - 0.5 - self.cx) / f * n,
                -(self.height - 0.5 - self.cy) / f * n, (self.cy + 0.5) / f * n)


Image = npt.NDArray[np.generic]


class Renderer(ABC):
    """Renders camera views of a backend's world (:meth:`Backend.renderer`).

    The simulation takes a :meth:`snapshot` on its own thread at the step an image belongs to; :meth:`render` then
    draws that snapshot, on another thread when :attr:`threaded` (the backend's state may have moved on by then),
    else at once on the simulation's thread.
    """

    threaded: ClassVar[bool] = False
    """Whether :meth:`render` may run on another thread, concurrently with :meth:`Backend.step`."""

    @abstractmethod
    def snapshot(self) -> object:
        """What :meth:`render` needs of the current state (a copy: the backend may step on)."""

    @abstractmethod
    def render(self, snapshot: object, views: Sequence[CameraView]) -> list[tuple[Image | None, Image | None]]:
        """Draw every view of ``snapshot``: per view ``(rgb, depth)``, rgb as (height, width, 3) uint8 (row 0 at
        the top), depth as (height, width) float32 distances along the optical axis [m] (+inf beyond ``far`` or
        where nothing is); None for what the view did not ask for."""

    def close(self) -> None:  # noqa: B027 - optional
        """Free the renderer's resources (on the thread that rendered); default: nothing."""


