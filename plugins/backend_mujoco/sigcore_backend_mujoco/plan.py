"""What the builder decided for each entity before compiling, and the model's collision/ray conventions.

Collision bits (``contype`` / ``conaffinity``; MuJoCo collides two geoms when ``ct1 & ca2 or ct2 & ca1``):

=====================  =======  ===========  =============================================================
geom state             contype  conaffinity  collides with
=====================  =======  ===========  =============================================================
normal                 1        1|2|4        normal, grasped, the ground, held people
grasped object         2        2            normal, grasped, the ground (not the robot holding it)
robot that grasps      1        1            normal, the ground, held people (not the objects it holds)
the ground plane       4        1|2          normal, grasped, grasping (not held people)
held person            8        1|2          normal, grasped, grasping (not the ground, not other held people)
collision off          0        0            nothing
=====================  =======  ===========  =============================================================

A held person's feet on the floor would be contacts the solver works on every step for nothing (the person is
put back after each step): 8 contacts, 30 % of a step of the clean-up world. Held people therefore do not touch
the ground or one another; a dynamic one (a mannequin) is normal.

Geom groups: every collision geom is in group 0, visual-only geoms (none today) in group 2. Rays see group 0
only; a ray cast that excludes an entity moves that entity's geoms to group 5 for the duration of the cast.
"""

from __future__ import annotations

from dataclasses import dataclass, field

BIT_NORMAL = 1
BIT_GRASPED = 2
BIT_GROUND = 4
BIT_HELD_PERSON = 8
NORMAL = (BIT_NORMAL, BIT_NORMAL | BIT_GRASPED | BIT_GROUND)
GRASPED = (BIT_GRASPED, BIT_GRASPED)
GRASPING = (BIT_NORMAL, BIT_NORMAL)
GROUND = (BIT_GROUND, BIT_NORMAL | BIT_GRASPED)
HELD_PERSON = (BIT_HELD_PERSON, BIT_NORMAL | BIT_GRASPED)
OFF = (0, 0)

GROUP_COLLISION = 0
GROUP_VISUAL = 2
GROUP_RAY_EXCLUDED = 5

FREE_JOINT = "__free__"
"""Name (after the entity prefix) of the free joint of a dynamic entity."""

GROUND_BODY = "world"


def prefix(entity: str) -> str:
    """Prefix of every MuJoCo element name of ``entity`` (entity names cannot contain ``/``)."""
    return f"{entity}/"


@dataclass(frozen=True)
class JointPlan:
    """A movable joint of a robot and its actuator.

    Attributes:
        name: URDF joint name.
        wheel: A drive wheel (velocity servo, always).
        kp: Position gain [N m/rad].
        kv: Damping of the position servo [N m s/rad].
        max_torque: Default torque limit [N m] of the actuator.
        limits: ``(lower, upper)`` [rad] or [m] of a revolute or prismatic joint; ``None`` if unlimited.
    """

    name: str
    wheel: bool
    kp: float
    kv: float
    max_torque: float
    limits: tuple[float, float] | None = None
    passive: bool = False
    """A person's joint: no actuator; moved by ``set_joint_angle`` and held there (kinematic)."""


@dataclass
class EntityPlan:
    """An entity as laid out in the spec.

    Attributes:
        name: Entity name; every body of the entity is named ``<name>/...``.
        kind: ``robot``, ``object`` or ``human``.
        parts: ``(part name, body name)``, main part first.
        free: Has a free joint (dynamic entities); otherwise the root body is welded to the world.
        held: Starts with dynamics off (a static human).
        joints: Movable joints in URDF order: a robot's actuated ones, a person's passive ones.
        total_mass: Scale the masses to this total [kg] after compiling (URDF objects given a ``mass``).
    """

    name: str
    kind: str
    parts: list[tuple[str, str]]
    free: bool
    held: bool = False
    joints: list[JointPlan] = field(default_factory=list)
    total_mass: float | None = None


@dataclass(frozen=True)
class WeldPlan:
    """A grasp weld, disabled at build, between a gripper part and a graspable object.

    Attributes:
        robot: The robot entity.
        part: Its gripper link.
        obj: The object entity.
        name: The equality constraint's name in the model.
    """

    robot: str
    part: str
    obj: str
    name: str


def lock_name(person: str, joint: str) -> str:
    """The joint equality that locks joint ``joint`` of ``person`` while the person is dynamic."""
    return f"lock:{person}:{joint}"
