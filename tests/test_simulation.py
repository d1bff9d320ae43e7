"""The simulation loop: lifecycle order and periods, collisions, messages, failures, determinism, reset."""

from __future__ import annotations

import logging

import numpy as np
import pytest
import trackers

from sigcore.sim import Simulation, run
from sigcore.sim.runner import RunControl
from sigcore.world import World, WorldError, parse_world


def test_lifecycle_order_and_periods(sim: Simulation) -> None:
    """on_init runs once before any on_action; on_action then runs every returned period, at those times."""
    trackers.CALLS.clear()
    tracker = trackers.Tracker()
    sim.entities.set_controller("moderator", tracker)
    sim.step(round(0.55 / sim.dt))
    calls = [(c, round(t, 6)) for a, c, t in trackers.CALLS if a == "moderator"]
    assert calls[0] == ("on_init", 0.0)
    actions = [t for c, t in calls if c == "on_action"]
    assert actions == pytest.approx([0.0, 0.1, 0.2, 0.3, 0.4, 0.5])
    assert [c for c, _ in calls].count("on_init") == 1


def test_only_overridden_callbacks_are_registered(sim: Simulation) -> None:
    """A controller overriding only on_action is never registered for collisions or messages."""
    ctrl = trackers.ActionOnly()
    sim.entities.set_controller("cube", ctrl)
    assert "cube" not in sim.entities.controllers.collision_listeners
    assert "cube" not in sim.entities.controllers.message_listeners
    sim.step(round(0.2 / sim.dt))
    assert ctrl.count == 5  # t = 0, 0.05, 0.10, 0.15, 0.20


def test_raising_controller_is_disabled_and_reported(sim: Simulation, caplog: pytest.LogCaptureFixture) -> None:
    """A controller that raises is disabled with its agent's name; the others and the simulation go on."""
    bad, good = trackers.Raising(), trackers.ActionOnly()
    sim.entities.set_controller("ball", bad)
    sim.entities.set_controller("heavy", good)
    with caplog.at_level(logging.ERROR, logger="sigcore"):
        sim.step(100)
    assert bad.count == 3
    assert good.count > 3
    assert [f.agent for f in sim.entities.controllers.failures] == ["ball"]
    assert "RuntimeError: boom" in sim.entities.controllers.failures[0].error
    assert "'ball'" in caplog.text
    assert sim.step_count == 100


def test_bad_period_disables_controller(sim: Simulation) -> None:
    """on_action returning a non-number is reported as a failure of that controller."""
    sim.entities.set_controller("ball", trackers.BadPeriod())
    sim.step(5)
    assert sim.entities.controllers.failures and "on_action must return" in sim.entities.controllers.failures[0].error


def test_collision_event_once_per_new_contact(sim: Simulation) -> None:
    """Dropping the ball onto the heavy box gives one event per new (part, other entity) pair, with both names."""
    tracker = trackers.Tracker()
    tracker.period = 100.0
    sim.entities.set_controller("ball", tracker)
    sim.step(10)
    tracker.events.clear()
    heavy = sim.agent("heavy").position()
    sim.agent("ball").set_position(heavy + np.array([0, 0, 0.5]))
    sim.step(round(1.0 / sim.dt))
    others = [e.other for e in tracker.events]
    assert others.count("heavy") == 1
    assert all(e.agent == "ball" and e.part == "main" for e in tracker.events)
    assert sim.agent("ball").collision_state("main")


def test_messages_reach_on_recv_msg(sim: Simulation) -> None:
    """send_msg reaches the recipient before the next step; broadcast_msg reaches every other agent."""
    receiver, other = trackers.Tracker(), trackers.Tracker()
    sim.entities.set_controller("moderator", receiver)
    sim.entities.set_controller("ball", other)
    sim.entities.set_controller("bot", trackers.Greeter())
    seen = []
    sim.events.subscribe("message", seen.append)
    sim.step(1)
    assert [(m.sender, m.content) for m in receiver.messages] == [("bot", "hello moderator"), ("bot", "hello all")]
    assert [m.content for m in other.messages] == ["hello all"]
    assert len(seen) == len(sim.entities) - 1 + 1


def test_world_controller_by_dotted_path(core_world: World, tmp_path) -> None:  # type: ignore[no-untyped-def]
    """A controller named in the world file by 'module:Class' is created and called."""
    text = (core_world.source.read_text().replace('<agent name="moderator"/>',
            '<agent name="moderator" controller="trackers:Tracker"/>'))
    path = core_world.source.parent / "_tmp_world_ctrl.xml"
    path.write_text(text)
    try:
        trackers.CALLS.clear()
        sim = Simulation(parse_world(path), "mujoco")
        sim.step(1)
        assert ("moderator", "on_init", 0.0) in trackers.CALLS
    finally:
        path.unlink()


def test_unknown_controller_is_a_located_world_error(core_world: World) -> None:
    """A controller that cannot be imported is reported at the controller attribute's line."""
    text = core_world.source.read_text().replace('<agent name="moderator"/>',
                                                 '<agent name="moderator" controller="nosuch.module:X"/>')
    path = core_world.source.parent / "_tmp_world_bad.xml"
    path.write_text(text)
    try:
        with pytest.raises(WorldError) as e:
            Simulation(parse_world(path), "mujoco")
        issue = e.value.issues[0]
        assert issue.attribute == "controller"
        assert issue.line == text.splitlines().index('  <agent name="moderator" controller="nosuch.module:X"/>') + 1
        assert "cannot import module 'nosuch.module'" in issue.message
    finally:
        path.unlink()


def _trajectory(world: World) -> list[bytes]:
    sim = Simulation(world, "mujoco")
    robot = sim.robot("bot")
    robot.set_wheel_velocity(4.0, 2.5)
    out = []
    for i in range(10):
        sim.step(100)
        if i == 3:
            sim.agent("ball").add_force((3.0, 0.0, 5.0))
        out.append(b"".join(np.concatenate(p).tobytes() for p in sim.poses().values()))
    return out


def test_determinism(core_world: World) -> None:
    """Two identical runs give bitwise-identical body poses at every sample."""
    assert _trajectory(core_world) == _trajectory(core_world)


def test_reset_restores_state_and_time_goes_on(sim: Simulation) -> None:
    """reset() puts bodies back to their initial poses; simulation time keeps increasing."""
    start = {k: v[0].copy() for k, v in sim.poses().items()}
    sim.robot("bot").set_wheel_velocity(5, 5)
    sim.step(500)
    t = sim.time
    assert np.linalg.norm(sim.agent("bot").position() - start["bot"]) > 0.3
    sim.reset()
    assert sim.time == t
    for name, pos in start.items():
        np.testing.assert_allclose(sim.agent(name).position(), pos, atol=1e-9)
    sim.step(1)
    assert sim.time > t


def test_run_modes_steps_duration_and_pause(sim: Simulation) -> None:
    """run() honours --steps and --duration; a paused run without a transport does not step."""
    report = run(sim, steps=50)
    assert report.steps == 50 and sim.step_count == 50
    report = run(sim, duration=0.1)
    assert report.steps == 50
    report = run(sim, steps=10, control=RunControl(paused=True))
    assert report.steps == 0


def test_realtime_factor_paces_the_run(sim: Simulation) -> None:
    """With a real-time factor of 2, 0.2 simulated seconds take about 0.1 wall seconds (not much less)."""
    report = run(sim, duration=0.2, realtime_factor=2.0)
    assert report.wall_time >= 0.095
    assert report.real_time_factor == pytest.approx(2.0, rel=0.25)


def test_lidar_scans_at_its_rate(sim: Simulation) -> None:
    """The lidar produces one scan per 1/rate simulated seconds, stamped with the sim time, in metres."""
    scans = []
    sim.events.subscribe("scan", scans.append)
    sim.step(round(0.5 / sim.dt))
    assert [round(s.stamp, 6) for s in scans] == [0.1, 0.2, 0.3, 0.4, 0.5]
    s = scans[-1]
    assert s.ranges.shape == (180,) and s.frame == "laser_link"
    wall_x = 3.0 - 0.05  # the wall's near face; the lidar looks along +x from x = 0.17
    forward = s.ranges[np.argmin(np.abs(s.angle_min + s.angle_increment * np.arange(180)))]
    assert forward == pytest.approx(wall_x - 0.17, abs=0.01)


def test_wheel_odometry_follows_the_drive(sim: Simulation) -> None:
    """Wheel odometry integrated each step ends within 3 cm / 0.05 rad of the true displacement after an arc."""
    odo = sim.entities.enable_odometry("bot")
    bot = sim.robot("bot")
    p0 = bot.position().copy()
    bot.set_base_velocity(0.3, 0.4)
    sim.step(round(3.0 / sim.dt))
    from sigcore.geometry import quat_yaw

    true_yaw = quat_yaw(bot.rotation())
    assert odo.state.x == pytest.approx(bot.position()[0] - p0[0], abs=0.03)
    assert odo.state.y == pytest.approx(bot.position()[1] - p0[1], abs=0.03)
    assert odo.state.yaw == pytest.approx(true_yaw, abs=0.05)
    assert odo.state.stamp == pytest.approx(sim.time)
