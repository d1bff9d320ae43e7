"""Helpers of the SLAM tests: the box room (tests/slam/data/box_room.xml) and a waypoint follower."""

from __future__ import annotations

import math
from pathlib import Path

from sigcore.geometry import quat_yaw
from sigcore.sim import Simulation
from sigcore.world import World, parse_world

DATA = Path(__file__).parent / "data"
ROOM = DATA / "box_room.xml"
ROBOT = "robot_000"
PLUGIN_LINE = '  <plugin name="slam" agent="robot_000" voxel_size="0.2" resolution="0.05" size="10 10"/>\n'


def room_world(plugin: str | None = PLUGIN_LINE) -> World:
    """The box room, its ``<plugin>`` line replaced by ``plugin`` (``None``: no plugin)."""
    text = ROOM.read_text()
    assert PLUGIN_LINE in text
    return parse_world(ROOM, text.replace(PLUGIN_LINE, plugin or ""))


def ground_truth(sim: Simulation) -> tuple[float, float, float]:
    """World (x, y, yaw) of robot_000's base_link."""
    pos, quat = sim.backend.get_pose(ROBOT)
    return float(pos[0]), float(pos[1]), quat_yaw(quat)


def drive_to(sim: Simulation, waypoints: list[tuple[float, float]], speed: float = 0.4) -> None:
    """Waypoint follower on the ground truth: turn in place towards each point, then drive to it."""
    robot = sim.robot(ROBOT)
    for wx, wy in waypoints:
        for _ in range(20_000):
            x, y, yaw = ground_truth(sim)
            dist = math.hypot(wx - x, wy - y)
            if dist < 0.05:
                break
            err = math.atan2(wy - y, wx - x) - yaw
            err = math.atan2(math.sin(err), math.cos(err))
            if abs(err) > 0.25:
                robot.set_base_velocity(0.0, max(-1.0, min(1.0, 2.0 * err)))
            else:
                robot.set_base_velocity(min(speed, 1.5 * dist + 0.05), 2.0 * err)
            sim.step(10)
    robot.set_base_velocity(0.0, 0.0)
    sim.step(250)
