"""A scripted clean-up robot (controller ``cleanup.robot``): the proof that the task is feasible, and the main job
of ``worlds/cleanup.xml`` until the ROS 2 example nodes exist.

Attach it to sigbot in the clean-up world (``controller="cleanup.robot"``). It uses ground truth (the robot's and
the items' poses), drives with ``set_base_velocity``, moves the arms with ``set_joint_target`` (closed-form IK, hand
pointing down), grasps with ``grasp`` once the hand is within the grasp radius, drops each item into the box that
accepts it, and stops.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator

import numpy as np

from sigcore.agent.controller import Controller
from sigcore.agent.exceptions import ApiError
from sigcore.agent.handle import SimObj
from sigcore.agent.robot import RobotObj
from sigcore.geometry import quat_conj, quat_rotate

from .arm import TUCK, Pose, hand_down, joint_names
from .drive import Follower
from .plan import Job, Stop, plan

PERIOD = 0.02
"""Control period [s]."""
GRASP_ABOVE = 0.03
"""Aim the grasp point this far above the item's centre [m]."""
HOVER = 0.90
"""Grasp point height before going down to an item [m] (the highest a hand pointing down reaches 0.5 m ahead)."""
DROP_HEIGHT = 0.65
"""Grasp point height when releasing over a box [m]."""

Script = Iterator[None]


class CleanupRobot(Controller):
    """Cleans up every trash item of the world, nearest first, then stands still.

    Attributes:
        done: Every job was carried out.
        finished_at: Simulation time when it was done [s].
        log: ``(time, text)`` of each step of the script, for people.
    """

    def __init__(self) -> None:
        self.done = False
        self.finished_at: float | None = None
        self.log: list[tuple[float, str]] = []
        self._script: Script | None = None

    def on_init(self, ctx: SimObj) -> None:
        if not isinstance(ctx, RobotObj):
            raise ApiError(f"cleanup.robot drives a robot; '{ctx.name}' is a {ctx.kind}")
        self.robot = ctx
        self.follower = Follower(ctx, PERIOD)
        self.radius = {g.part: g.grasp_radius for g in ctx.sim.entities.robot_model(ctx.name).grippers}
        self._script = self._run(plan(ctx.sim))

    def on_action(self, ctx: SimObj) -> float:
        if self._script is not None:
            try:
                next(self._script)
            except StopIteration:
                self._script = None
        return PERIOD

    # ------------------------------------------------------------------ the script
    def _note(self, text: str) -> None:
        self.log.append((round(self.robot.time, 6), text))

    def _run(self, jobs: list[Job]) -> Script:
        yield from self._arm("l", TUCK, 1.0)
        yield from self._arm("r", TUCK, 0.2)
        while jobs:
            x, y, _ = self.follower.pose()
            job = min(jobs, key=lambda j: math.hypot(j.pick.x - x, j.pick.y - y))
            jobs.remove(job)
            yield from self._clean(job)
        while not self.follower.stop():
            yield
        self.done, self.finished_at = True, round(self.robot.time, 6)
        self._note("done")

    def _clean(self, job: Job) -> Script:
        hand = f"{job.side}_hand_link"
        self._note(f"going to pick {job.item} with {hand}")
        yield from self._approach(job.pick)
        yield from self._pick(job.side, hand, job.item)
        yield from self._until(lambda: self.follower.go_to(job.pick.stage_x, job.pick.stage_y, backwards=True))
        if not self.robot.sim.entities.grasps.is_held(job.item):
            self._note(f"could not grasp {job.item}; skipping it")
            return
        self._note(f"carrying {job.item} to {job.box}")
        yield from self._approach(job.drop)
        yield from self._drop(job.side, hand, job.box)
        yield from self._until(lambda: self.follower.go_to(job.drop.stage_x, job.drop.stage_y, backwards=True))

    def _approach(self, stop: Stop) -> Script:
        yield from self._until(lambda: self.follower.go_to(stop.stage_x, stop.stage_y))
        yield from self._until(lambda: self.follower.turn_to(stop.yaw))
        yield from self._until(lambda: self.follower.go_to(stop.x, stop.y))
        yield from self._until(lambda: self.follower.turn_to(stop.yaw))

    def _pick(self, side: str, hand: str, item: str) -> Script:
        x, y, z = self._in_base(self.robot.get_obj(item).position())
        yield from self._arm(side, hand_down(side, x, y, HOVER), 1.2)
        radius = self.radius[hand] - 0.01

        def grasped() -> bool:
            if float(np.linalg.norm(self.robot.part_position(hand) - self.robot.get_obj(item).position())) < radius:
                self.robot.grasp(hand, item)
                self._note(f"grasped {item}")
                return True
            return False

        yield from self._arm(side, hand_down(side, x, y, z + GRASP_ABOVE), 1.0, stop_when=grasped)
        if not self.robot.sim.entities.grasps.is_held(item):
            grasped()
        yield from self._arm(side, TUCK, 1.2)

    def _drop(self, side: str, hand: str, box: str) -> Script:
        x, y, _ = self._in_base(self.robot.get_obj(box).position())
        yield from self._arm(side, hand_down(side, x, y, DROP_HEIGHT), 1.2)
        yield from self._wait(0.3)
        released = self.robot.release(hand)
        self._note(f"released {released} over {box}")
        yield from self._wait(0.3)
        yield from self._arm(side, TUCK, 1.0)

    # ------------------------------------------------------------------ motions
    def _in_base(self, point: np.ndarray) -> tuple[float, float, float]:
        local = quat_rotate(quat_conj(self.robot.rotation()), point - self.robot.position())
        return float(local[0]), float(local[1]), float(point[2])

    def _until(self, done: Callable[[], bool]) -> Script:
        while not done():
            yield

    def _wait(self, seconds: float) -> Script:
        for _ in range(max(1, round(seconds / PERIOD))):
            self.follower.stop()
            yield

    def _arm(self, side: str, target: Pose, duration: float, stop_when: Callable[[], bool] | None = None) -> Script:
        """Move an arm to ``target`` along a smooth joint-space ramp of ``duration`` [s], then let it settle."""
        names = joint_names(side)
        start = [self.robot.joint_angle(j) for j in names]
        steps = max(1, round(duration / PERIOD))
        for k in range(1, steps + 1):
            s = k / steps
            s = s * s * (3 - 2 * s)
            for name, a, b in zip(names, start, target, strict=True):
                self.robot.set_joint_target(name, a + s * (b - a))
            self.follower.stop()
            if stop_when is not None and stop_when():
                return
            yield
        for _ in range(25):
            if max(abs(self.robot.joint_angle(j) - b) for j, b in zip(names, target, strict=True)) < 0.03:
                return
            self.follower.stop()
            yield
