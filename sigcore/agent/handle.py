"""The agent handle: SIGVerse's SimObj / RobotObj operations in Python.

Every method validates its input and raises :class:`~sigcore.agent.exceptions.ApiError` with a message saying what
was wrong and what would be valid; nothing here can stop the simulation. Units are SI, frames are the world frame
(z up) unless a method says "relative", which means the entity's main-part frame.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from typing import TYPE_CHECKING

import numpy as np

from ..backend import MAIN, Array
from ..geometry import angle_between, cross, normalized, quat_from_axis_angle, quat_rotate
from ..text import quote
from .exceptions import ApiError

if TYPE_CHECKING:
    from ..sim.simulation import Simulation


LIMITS = {"position": 1e4, "velocity": 1e3, "angular velocity": 1e3, "force": 1e6, "torque": 1e6,
          "acceleration": 1e4}
"""Largest magnitude accepted per component, by quantity (a guard against values that would blow the solver up)."""

MIN_MASS = 1e-3
"""Smallest total mass ``set_mass`` accepts [kg]: lighter bodies make the engines' inertia matrices singular."""


def _vec(values: Iterable[float], what: str, n: int = 3) -> Array:
    try:
        arr = np.asarray(list(values), dtype=float)
    except (TypeError, ValueError):
        raise ApiError(f"{what} must be {n} numbers, got {values!r}") from None
    if arr.shape != (n,):
        raise ApiError(f"{what} must have {n} numbers, got {arr.size}")
    if not np.all(np.isfinite(arr)):
        raise ApiError(f"{what} must be finite numbers, got {arr.tolist()}")
    limit = LIMITS.get(what.split(" [")[0], 1e6)
    if np.any(np.abs(arr) > limit):
        raise ApiError(f"{what} components must be within ±{limit:g}, got {arr.tolist()}")
    return arr


def _num(value: float, what: str, *, low: float | None = None, high: float | None = None,
         strict_low: bool = False) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ApiError(f"{what} must be a number, got {quote(repr(value))}") from None
    if not math.isfinite(v):
        raise ApiError(f"{what} must be a finite number, got {v}")
    if low is not None and (v <= low if strict_low else v < low):
        raise ApiError(f"{what} must be {'>' if strict_low else '>='} {low}, got {v}")
    if high is not None and v > high:
        raise ApiError(f"{what} must be <= {high}, got {v}")
    return v


class SimObj:
    """Handle of one agent: an object, a human, a robot (see :class:`RobotObj`) or a bare agent.

    Bare agents (no body) have only the messaging and world-query methods; body methods raise ``ApiError``.
    """

    def __init__(self, sim: Simulation, name: str, kind: str) -> None:
        self.sim = sim
        self.name = name
        self.kind = kind
        self._has_body = kind != "agent"

    def __repr__(self) -> str:
        return f"<{type(self).__name__} {self.name!r} ({self.kind})>"

    # ------------------------------------------------------------------ world queries and messages
    @property
    def time(self) -> float:
        """Simulation time [s]."""
        return self.sim.time

    def entities(self) -> list[str]:
        """Names of every agent of the world (bodies and bare agents)."""
        return list(self.sim.entities)

    def get_obj(self, name: str) -> SimObj:
        """Handle of another agent by name."""
        return self.sim.agent(name)

    def send_msg(self, to: str, text: str) -> None:
        """Send ``text`` to agent ``to``; delivered to its ``on_recv_msg`` before the next step."""
        self.sim.send_msg(self.name, to, text)

    def broadcast_msg(self, text: str) -> None:
        """Send ``text`` to every other agent."""
        self.sim.broadcast_msg(self.name, text)

    # ------------------------------------------------------------------ internal helpers
    def _body(self) -> None:
        if not self._has_body:
            raise ApiError(f"'{self.name}' is a bare agent with no body; name an entity instead "
                           f"(entities: {', '.join(self.sim.entities.names)})")

    def _part(self, part: str | None) -> str | None:
        self._body()
        if part is None or part == "" or part == MAIN:
            return None
        parts = self.sim.backend.parts(self.name)
        if part not in parts:
            raise ApiError(f"'{self.name}' has no part {quote(part)}; parts: {', '.join([MAIN, *parts[1:]])}")
        return part

    def _dynamic(self, what: str) -> None:
        if not self.sim.entities.mode(self.name, "dynamics"):
            raise ApiError(f"{what} needs dynamics on for '{self.name}' (set dynamics mode true first)")

    # ------------------------------------------------------------------ pose
    def position(self) -> Array:
        """Position [m] of the main part's frame."""
        self._body()
        return self.sim.backend.get_pose(self.name)[0]

    def set_position(self, xyz: Iterable[float]) -> None:
        """Teleport to position ``xyz`` [m], keeping the orientation."""
        self._body()
        self.sim.backend.set_pose(self.name, position=_vec(xyz, "position"))

    def rotation(self) -> Array:
        """Orientation quaternion (w, x, y, z)."""
        self._body()
        return self.sim.backend.get_pose(self.name)[1]

    def set_rotation(self, wxyz: Iterable[float]) -> None:
        """Set the orientation (quaternion w, x, y, z; normalised here, must be non-zero)."""
        self._body()
        q = _vec(wxyz, "quaternion (qw qx qy qz)", 4)
        if float(np.linalg.norm(q)) < 1e-9:
            raise ApiError("quaternion (qw qx qy qz) must be non-zero, e.g. 1 0 0 0 for no rotation")
        self.sim.backend.set_pose(self.name, quaternion=normalized(q))

    def set_axis_and_angle(self, axis: Iterable[float], angle: float) -> None:
        """Set the orientation as a rotation of ``angle`` [rad] about ``axis`` (non-zero)."""
        self._body()
        a = _vec(axis, "axis")
        if float(np.linalg.norm(a)) < 1e-12:
            raise ApiError("axis must be non-zero, e.g. 0 0 1")
        self.sim.backend.set_pose(self.name, quaternion=quat_from_axis_angle(a, _num(angle, "angle")))

    def part_position(self, part: str) -> Array:
        """Position [m] of one part's frame (``"main"`` = main part)."""
        return self.sim.backend.get_pose(self.name, self._part(part))[0]

    def part_rotation(self, part: str) -> Array:
        """Orientation (w, x, y, z) of one part's frame."""
        return self.sim.backend.get_pose(self.name, self._part(part))[1]

    def parts(self) -> list[str]:
        """Part names (``"main"`` first)."""
        self._body()
        return [MAIN, *self.sim.backend.parts(self.name)[1:]]

    # ------------------------------------------------------------------ velocities
    def velocity(self) -> Array:
        """Linear velocity [m/s] of the main part."""
        self._body()
        return self.sim.backend.get_velocity(self.name)[0]

    def set_velocity(self, v: Iterable[float]) -> None:
        """Set the linear velocity [m/s]."""
        self._body()
        self.sim.backend.set_velocity(self.name, linear=_vec(v, "velocity"))

    def angular_velocity(self) -> Array:
        """Angular velocity [rad/s] of the main part."""
        self._body()
        return self.sim.backend.get_velocity(self.name)[1]

    def set_angular_velocity(self, w: Iterable[float]) -> None:
        """Set the angular velocity [rad/s]."""
        self._body()
        self.sim.backend.set_velocity(self.name, angular=_vec(w, "angular velocity"))

    # ------------------------------------------------------------------ forces (next step only)
    def add_force(self, f: Iterable[float], part: str | None = None) -> None:
        """Add a force [N] (world frame) at the centre of mass of the main part (or ``part``)."""
        p = self._part(part)
        self._dynamic("add_force")
        self.sim.add_wrench(self.name, p, _vec(f, "force"), np.zeros(3))

    def set_force(self, f: Iterable[float]) -> None:
        """Replace the force [N] (world frame) applied at the centre of mass during the next step."""
        self._body()
        self._dynamic("set_force")
        self.sim.set_wrench(self.name, None, force=_vec(f, "force"))

    def set_accel(self, a: Iterable[float]) -> None:
        """Accelerate the entity by ``a`` [m/s^2] during the next step (a force of total mass times ``a``)."""
        self._body()
        self._dynamic("set_accel")
        self.sim.set_wrench(self.name, None, force=_vec(a, "acceleration") * self.mass())

    def add_rel_force(self, f: Iterable[float]) -> None:
        """Add a force [N] given in the entity's frame, at its centre of mass."""
        self.add_force(quat_rotate(self.rotation(), _vec(f, "force")))

    def add_force_at_pos(self, f: Iterable[float], pos: Iterable[float]) -> None:
        """Add a world-frame force [N] at a world point [m] (adds the torque about the centre of mass)."""
        self._body()
        self._dynamic("add_force_at_pos")
        self._force_at(_vec(f, "force"), _vec(pos, "position"))

    def add_force_at_rel_pos(self, f: Iterable[float], pos: Iterable[float]) -> None:
        """Add a world-frame force [N] at a point given in the entity's frame [m]."""
        self._body()
        self._dynamic("add_force_at_rel_pos")
        self._force_at(_vec(f, "force"), self._to_world(_vec(pos, "position")))

    def add_rel_force_at_pos(self, f: Iterable[float], pos: Iterable[float]) -> None:
        """Add a force [N] given in the entity's frame at a world point [m]."""
        self._body()
        self._dynamic("add_rel_force_at_pos")
        self._force_at(quat_rotate(self.rotation(), _vec(f, "force")), _vec(pos, "position"))

    def add_rel_force_at_rel_pos(self, f: Iterable[float], pos: Iterable[float]) -> None:
        """Add a force [N] given in the entity's frame at a point in the entity's frame [m]."""
        self._body()
        self._dynamic("add_rel_force_at_rel_pos")
        self._force_at(quat_rotate(self.rotation(), _vec(f, "force")), self._to_world(_vec(pos, "position")))

    def add_force_to_part(self, part: str, f: Iterable[float]) -> None:
        """Add a world-frame force [N] at the centre of mass of ``part``."""
        if self._part(part) is None and part not in ("", MAIN):
            raise ApiError(f"unknown part {quote(part)}")
        self.add_force(f, part=part)

    def set_torque(self, t: Iterable[float]) -> None:
        """Replace the torque [N m] (world frame) applied during the next step."""
        self._body()
        self._dynamic("set_torque")
        self.sim.set_wrench(self.name, None, torque=_vec(t, "torque"))

    def add_torque(self, t: Iterable[float]) -> None:
        """Add a torque [N m] (world frame) for the next step."""
        self._body()
        self._dynamic("add_torque")
        self.sim.add_wrench(self.name, None, np.zeros(3), _vec(t, "torque"))

    def _to_world(self, rel: Array) -> Array:
        pos, quat = self.sim.backend.get_pose(self.name)
        return pos + quat_rotate(quat, rel)

    def _force_at(self, force: Array, point: Array) -> None:
        com = self.sim.backend.get_com(self.name)
        self.sim.add_wrench(self.name, None, force, cross(point - com, force))

    # ------------------------------------------------------------------ properties and modes
    def mass(self) -> float:
        """Total mass [kg]."""
        self._body()
        return self.sim.backend.get_mass(self.name)

    def set_mass(self, mass: float) -> None:
        """Set the total mass [kg] (``MIN_MASS`` to 1e6; parts are scaled together)."""
        self._body()
        self.sim.backend.set_mass(self.name, _num(mass, "mass [kg]", low=MIN_MASS, high=1e6))

    def gravity_mode(self) -> bool:
        """Whether gravity acts on the entity."""
        self._body()
        return self.sim.entities.mode(self.name, "gravity")

    def set_gravity_mode(self, enabled: bool) -> None:
        """Switch gravity on or off for this entity."""
        self._body()
        self.sim.entities.set_mode(self.name, "gravity", bool(enabled))

    def dynamics_mode(self) -> bool:
        """Whether the entity is simulated (True) or held kinematically (False)."""
        self._body()
        return self.sim.entities.mode(self.name, "dynamics")

    def set_dynamics_mode(self, enabled: bool) -> None:
        """Simulate the entity (True) or hold it where it is, movable only by set_position/joint angles."""
        self._body()
        self.sim.entities.set_mode(self.name, "dynamics", bool(enabled))

    def collision_enable(self) -> bool:
        """Whether the entity collides."""
        self._body()
        return self.sim.entities.mode(self.name, "collision")

    def set_collision_enable(self, enabled: bool) -> None:
        """Switch collisions on or off for this entity."""
        self._body()
        self.sim.entities.set_mode(self.name, "collision", bool(enabled))

    # ------------------------------------------------------------------ contacts and grasping state
    def collision_state(self, part: str = MAIN) -> bool:
        """Whether ``part`` (``"main"`` = main part) touches another entity now."""
        p = self._part(part)
        own = p if p is not None else self.sim.backend.parts(self.name)[0]
        return any(e == self.name and q == own for e, q, _ in self.sim.contact_triples())

    def is_grasped(self) -> bool:
        """Whether a robot holds this entity."""
        self._body()
        return self.sim.entities.grasps.is_held(self.name)

    def set_owner(self, part: str, owner: str) -> None:
        """Record agent ``owner`` as the owner of ``part`` (``"main"`` = main part); informational."""
        resolved = self._part(part) or MAIN
        self.sim.agent(owner)  # must exist
        self.sim.entities.owners.set(self.name, resolved, owner)

    def owner(self, part: str = MAIN) -> str | None:
        """The owner recorded for ``part``, or None."""
        return self.sim.entities.owners.get(self.name, self._part(part) or MAIN)

    # ------------------------------------------------------------------ queries on vectors
    @staticmethod
    def angle_to_axis(axis: str, v: Iterable[float]) -> float:
        """Angle [rad] between vector ``v`` and world axis ``"x"``, ``"y"`` or ``"z"``.

        The original sig_ros returned the cosine of that angle; sigcore returns the angle.
        """
        axes = {"x": (1.0, 0.0, 0.0), "y": (0.0, 1.0, 0.0), "z": (0.0, 0.0, 1.0)}
        if axis not in axes:
            raise ApiError(f"axis must be one of x, y, z, got {quote(axis)}")
        vec = _vec(v, "vector")
        if float(np.linalg.norm(vec)) == 0.0:
            raise ApiError("vector must be non-zero")
        return angle_between(vec, np.array(axes[axis]))
