"""A procedural walking gait: a person's pose and joint angles, step by step in simulated time, from a velocity.

No engine is involved: :class:`Gait` turns a commanded forward speed and turn rate into, at each step, the pose of the
person's feet frame and the angles of its REP-155 joints (:mod:`sigcore.world.body`), which the caller applies to
the backend's held body.

* **Footholds, not joint curves.** The stance foot is planted where it landed, in the world; the swing foot moves
  from where it lifted off to its next foothold, half a step ahead of where the pelvis will be when it lands (beside
  it when the person stops or turns on the spot), lifted by up to 7 % of the leg's length. Each leg's hip, knee and
  ankle angles come from the foot's position by two-link inverse kinematics in the hip's frame (the hip yaw points
  the foot, the hip roll reaches sideways, the ankle keeps the foot flat). A foot on the ground therefore does not
  slide, whatever the speed or the turn.
* **The phase goes with the distance walked.** A step ends when the pelvis has advanced one step length (half of one
  for the first step from standing, or, on the spot, after turning by :data:`TURN_PER_STEP`); the step length grows
  with the speed (:func:`step_length`), so the cadence does too (about 2.3 steps/s at 1.4 m/s for a person of
  1.7 m). When the command stops, the step under way ends within :data:`SETTLE` seconds and the person stands on
  both feet.
* **The pelvis bobs.** Its height is the standing hip height, lowered where the legs would not reach the footholds.
* **The arms swing** against the legs: each shoulder flexes against its own side's foot, the elbows bend a little.

Units: m, s, rad. The gait is deterministic: the same commands at the same steps give the same angles bit for bit.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from ..geometry import wrap_angle
from ..world.body import Body

MAX_SPEED = 1.8
"""Fastest walk forward [m/s] (a brisk walk; faster is a run, which the gait does not do)."""
MAX_BACKWARD = 0.6
"""Fastest walk backward [m/s]."""
MAX_TURN = 2.0
"""Fastest turn [rad/s]."""
TURN_PER_STEP = 0.5
"""How far a person turns on the spot in one step [rad]."""
SETTLE = 0.35
"""Longest time [s] the step under way takes to end once the person is told to stop."""
_REACH = 0.995
"""The legs never straighten fully: a foothold is reached with at most this share of thigh + shank."""
_ARM_SWING = 0.9
"""Shoulder flexion [rad] per metre of the same-side foot behind the pelvis."""


def step_length(speed: float, height: float) -> float:
    """The step length [m] at ``speed`` [m/s] for a person ``height`` [m] tall: 0.36 x height at 1.4 m/s, as the
    square root of the speed, at least 0.12 x height (REP-155's legs are 0.42 x height from hip to ankle: longer
    steps would drop the pelvis more than the 4-5 cm a walk bobs)."""
    return max(0.12 * height, 0.36 * height * math.sqrt(abs(speed) / 1.4))


def check_command(linear: float, angular: float) -> str | None:
    """What is wrong with a walking command (None: nothing), naming the valid ranges."""
    if not (math.isfinite(linear) and math.isfinite(angular)):
        return f"linear {linear!r} m/s and angular {angular!r} rad/s must be finite numbers"
    if not -MAX_BACKWARD <= linear <= MAX_SPEED:
        return (f"a person walks at -{MAX_BACKWARD:g} to {MAX_SPEED:g} m/s (backward to forward), got linear "
                f"{linear:g} m/s")
    if abs(angular) > MAX_TURN:
        return f"a person turns at most {MAX_TURN:g} rad/s either way, got angular {angular:g} rad/s"
    return None


@dataclass
class Posture:
    """Where a person is at one step: its feet frame (``x``, ``y``, ``z`` [m], ``yaw`` [rad]) and its joint angles
    [rad] by REP-155 name."""

    x: float
    y: float
    z: float
    yaw: float
    angles: dict[str, float]


@dataclass
class _Foot:
    x: float
    y: float
    yaw: float


class Gait:
    """One person's walk (see the module docstring).

    Args:
        body: The person's body (its leg lengths, hip width, ankle height).
        x, y, z, yaw: Where its feet frame stands now (``z``: the floor's height there) [m, rad].
    """

    def __init__(self, body: Body, x: float, y: float, z: float, yaw: float) -> None:
        self.body = body
        self.x, self.y, self.floor, self.yaw = x, y, z, yaw
        self.linear = self.angular = 0.0
        joints = {j.name: j for j in body.joints}
        self._hip_y = joints["l_y_hip"].xyz[1]
        self._lift = 0.07 * (body.thigh + body.shank)
        self.feet = {side: self._beside(side, x, y, yaw) for side in ("l", "r")}
        self.swing: str | None = None
        """The foot in the air ("l", "r"), None while both are down."""
        self.progress = 0.0
        """How far the swing foot is on its way, 0 to 1."""
        self._start = _Foot(0.0, 0.0, 0.0)
        self._next = "r"
        self._half = False

    @staticmethod
    def _next_after(side: str) -> str:
        return "l" if side == "r" else "r"

    def _beside(self, side: str, x: float, y: float, yaw: float, ahead: float = 0.0) -> _Foot:
        """The foothold of foot ``side`` when the feet frame is at ``(x, y, yaw)``, ``ahead`` [m] forward of it."""
        lateral = self._hip_y if side == "l" else -self._hip_y
        c, s = math.cos(yaw), math.sin(yaw)
        return _Foot(x + c * ahead - s * lateral, y + s * ahead + c * lateral, yaw)

    def command(self, linear: float, angular: float) -> None:
        """Walk at ``linear`` [m/s] forward and turn at ``angular`` [rad/s] from now on (0, 0: stop).

        Raises:
            ValueError: a value out of range or not finite (:func:`check_command` says which).
        """
        problem = check_command(linear, angular)
        if problem is not None:
            raise ValueError(problem)
        self.linear, self.angular = float(linear), float(angular)

    @property
    def moving(self) -> bool:
        """Whether the person walks, turns or is finishing a step."""
        return self.linear != 0.0 or self.angular != 0.0 or self.swing is not None

    def advance(self, dt: float) -> Posture:
        """Move on by ``dt`` [s] and return the posture there."""
        v, w = self.linear, self.angular
        if v or w:
            mid = self.yaw + 0.5 * w * dt
            self.x += v * dt * math.cos(mid)
            self.y += v * dt * math.sin(mid)
            self.yaw += w * dt
        length = step_length(v, self.body.height)
        rate = max(abs(v) / length, abs(w) / TURN_PER_STEP)  # steps per second
        if self.swing is None and rate > 0.0:
            self.swing, self.progress = self._next, 0.0
            foot = self.feet[self.swing]
            self._start = _Foot(foot.x, foot.y, foot.yaw)
            other = self.feet[self._next_after(self.swing)]
            # from standing, the first step is a half step: the feet side by side, the pelvis moves half a step
            self._half = abs(_along(foot, self.yaw) - _along(other, self.yaw)) < 0.25 * length
        if self.swing is not None:
            rate = max(rate, 1.0 / SETTLE) if rate == 0.0 else rate * (2.0 if self._half else 1.0)
            self.progress = min(1.0, self.progress + rate * dt)
            left = (1.0 - self.progress) / rate  # time to touchdown
            yaw_td = self.yaw + w * left
            mid = self.yaw + 0.5 * w * left
            x_td = self.x + v * left * math.cos(mid)
            y_td = self.y + v * left * math.sin(mid)
            target = self._beside(self.swing, x_td, y_td, yaw_td, math.copysign(0.5 * length, v) if v else 0.0)
            u = self.progress
            smooth = u * u * (3.0 - 2.0 * u)
            s = self._start
            foot = _Foot(s.x + (target.x - s.x) * smooth, s.y + (target.y - s.y) * smooth,
                         s.yaw + wrap_angle(target.yaw - s.yaw) * smooth)
            self.feet[self.swing] = foot
            lift = self._lift * math.sin(math.pi * u)
            if self.progress >= 1.0:
                self._next = self._next_after(self.swing)
                self.swing, lift, self._half = None, 0.0, False
            return self._posture(lift)
        return self._posture(0.0)

    def _posture(self, lift: float) -> Posture:
        """The feet frame and every leg and arm angle for the feet where they are (the swing foot ``lift`` up)."""
        b = self.body
        a, sh = b.thigh, b.shank
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        reach = _REACH * (a + sh)
        local: dict[str, tuple[float, float, float, float]] = {}
        hip_z = b.hip_height
        for side, foot in self.feet.items():
            lateral = self._hip_y if side == "l" else -self._hip_y
            dx, dy = foot.x - self.x, foot.y - self.y
            fx, fy = c * dx + s * dy, -s * dx + c * dy - lateral  # the ankle from the hip, in the pelvis frame
            fz = b.ankle_height + (lift if side == self.swing else 0.0)
            local[side] = (fx, fy, fz, wrap_angle(foot.yaw - self.yaw))
            horizontal = fx * fx + fy * fy
            if horizontal < reach * reach:
                hip_z = min(hip_z, fz + math.sqrt(reach * reach - horizontal))
        angles: dict[str, float] = {}
        for side, (fx, fy, fz, turn) in local.items():
            sign = 1.0 if side == "l" else -1.0
            ct, st = math.cos(-turn), math.sin(-turn)  # undo the hip yaw
            x, y, z = ct * fx - st * fy, st * fx + ct * fy, fz - hip_z
            roll = math.atan2(y, -z)
            down = math.hypot(y, z)
            dist = min(max(math.hypot(x, down), abs(a - sh) + 1e-6), a + sh - 1e-6)
            knee = math.pi - math.acos(_clip((a * a + sh * sh - dist * dist) / (2 * a * sh)))
            hip = math.atan2(x, down) + math.acos(_clip((a * a + dist * dist - sh * sh) / (2 * a * dist)))
            angles[f"{side}_y_hip"] = -turn
            angles[f"{side}_p_hip"] = sign * roll
            angles[f"{side}_r_hip"] = hip
            angles[f"{side}_knee"] = -knee
            angles[f"{side}_ankle"] = -(hip - knee)
            swing = -_ARM_SWING * fx if self.swing is not None or self.linear else 0.0
            angles[f"{side}_y_shoulder"] = sign * math.pi / 2
            angles[f"{side}_p_shoulder"] = sign * swing
            angles[f"{side}_r_shoulder"] = sign * math.pi / 2
            angles[f"{side}_elbow"] = 0.2 + 0.4 * max(0.0, swing)
        return Posture(self.x, self.y, self.floor + hip_z - b.hip_height, self.yaw, angles)


def _along(foot: _Foot, yaw: float) -> float:
    """How far forward ``foot`` is along heading ``yaw`` [m] (from the world's origin: differences count)."""
    return foot.x * math.cos(yaw) + foot.y * math.sin(yaw)


def _clip(v: float) -> float:
    return min(1.0, max(-1.0, v))
