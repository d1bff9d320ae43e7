"""What the builder made of each entity: PyBullet body and link indices, joints and their drives.

Part ids, used by contacts, are: 0 for the ground, then one per entity part (a robot's or a person's link; the
single ``main`` of an object, which every link of a URDF object maps to) -- the MuJoCo backend's numbering.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

from sigcore.backend import find_joint, find_part

BASE = -1
"""PyBullet's link index of a body's base (a robot's root link)."""

# Collision filter bits. PyBullet 3.2.7's default collision filter collides two links when
# ``g1 & m2 or g2 & m1`` (measured: not Bullet's usual "and"), and a ray (group 1) hits a link when
# ``g & ray_mask and 1 & m``. Setting any filter replaces Bullet's own static/static exclusion, so static links
# (the ground, static objects, a fixed robot's base) get a group of their own:
#
#   link state        group  mask     collides with       seen by rays (mask 4)
#   dynamic           2|4    1|2|8    dynamic, static     yes
#   static            8|4    1        dynamic             yes
#   collision off     4      1        nothing             yes (as in the MuJoCo backend)
#
# A held person's links are "static" (see ``EntityIndex.still``): it touches what moves, not the ground, a static
# object or another held person (contacts that would cost solver rows every step and push nothing).
GROUP_DYNAMIC = 2 | 4
MASK_DYNAMIC = 1 | 2 | 8
GROUP_STATIC = 8 | 4
MASK_STATIC = 1
GROUP_OFF = 4
MASK_OFF = 1
RAY_MASK = 4
"""``collisionFilterMask`` of lidar rays."""


@dataclass
class JointIndex:
    """A movable joint of a robot or a person, and its drive (a person's joints have none).

    Attributes:
        index: PyBullet joint index (= the child link's index).
        wheel: A drive wheel (always velocity-controlled).
        max_torque: Default torque limit [N m] of its motor.
        position_gain: Speed [1/s] at which its position servo closes the error (``kp / kv``, at most
            ``1 / dt``).
        kp: Position gain [N m/rad] of its servo (the world's ``<gains>``).
        kv: Damping [N m s/rad] of its servo.
        initial: Joint position at build [rad] or [m].
    """

    index: int
    wheel: bool
    max_torque: float
    position_gain: float = 0.0
    kp: float = 0.0
    kv: float = 0.0
    initial: float = 0.0


@dataclass
class EntityIndex:
    """Where an entity lives in the PyBullet world.

    Attributes:
        name: Entity name.
        kind: ``robot``, ``object`` or ``human``.
        body: PyBullet body unique id.
        parts: Part names, main part first.
        part_link: Link index of each part (``BASE`` for the main part; ``"main"`` too, for robots).
        links: Every link index of the body, ``BASE`` first.
        welded: The base is fixed in the world (static object, fixed robot).
        joints: Movable joints by URDF name, in URDF order.
        held0: Dynamics off at build (static humans).
        rigid: A person built as a rigid mannequin (its joints fixed at their angles; see :mod:`.builder`).
        still: A held person: every link collides as a static one (set by the backend when it holds it).
        local_pos: Inertial frame origin of the base in its link frame [m].
        local_orn: Its orientation ``(x, y, z, w)``.
        masses0: Mass [kg] of each link in ``links`` at build (what ``get_mass`` sums).
        inertia0: Local inertia diagonal of each link at build [kg m^2].
    """

    name: str
    kind: str
    body: int
    parts: list[str]
    part_link: dict[str, int]
    links: list[int]
    welded: bool
    joints: dict[str, JointIndex] = field(default_factory=dict)
    held0: bool = False
    rigid: bool = False
    still: bool = False
    local_pos: tuple[float, float, float] = (0.0, 0.0, 0.0)
    local_orn: tuple[float, float, float, float] = (0.0, 0.0, 0.0, 1.0)
    masses0: list[float] = field(default_factory=list)
    inertia0: list[tuple[float, float, float]] = field(default_factory=list)

    def filter_bits(self, link: int, enabled: bool) -> tuple[int, int]:
        """Collision filter ``(group, mask)`` of one of its links with collision on or off."""
        if not enabled:
            return GROUP_OFF, MASK_OFF
        if self.still or (link == BASE and self.welded):
            return GROUP_STATIC, MASK_STATIC
        return GROUP_DYNAMIC, MASK_DYNAMIC

    @cached_property
    def joint_indices(self) -> list[int]:
        """The PyBullet indices of :attr:`joints`, in URDF order."""
        return [j.index for j in self.joints.values()]

    @property
    def static(self) -> bool:
        """Nothing of it can move: welded and without joints (a static object)."""
        return self.welded and not self.joints

    def link(self, part: str | None) -> int:
        """Link index of ``part`` (``None`` or ``"main"``: the base).

        Raises:
            BackendRefusal: no such part; the message lists the valid ones.
        """
        return BASE if part is None else find_part(self.kind, self.name, self.part_link, part, self.parts)

    def joint(self, name: str) -> JointIndex:
        """The movable joint ``name``; :class:`BackendRefusal` listing the valid joints otherwise."""
        return find_joint(self.kind, self.name, self.joints, name)
