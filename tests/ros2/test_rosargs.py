"""sigcore run WORLD ... --ros-args: remapping, namespace, parameters and log level reach the ROS 2 transport."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

pytest.importorskip("rclpy", reason="rclpy (ROS 2 Jazzy wheels) is not importable")

from rosproc import WORLD, ros_env, start_sim  # noqa: E402

pytestmark = pytest.mark.ros2


def test_remap_namespace_and_a_rate_parameter(tmp_path: Path) -> None:
    """-r /clock:=/sim_clock moves /clock, -r __ns:=/ns1 moves the relative (sig_ros) names and the node, and
    -p state_rate:=10 makes odom 10 Hz of simulated time; absolute names stay."""
    sim = start_sim(tmp_path, WORLD, "--realtime", "--wait-for", "/clock", "--wait-timeout", "0.1",
                    "--ros-args", "-r", "/clock:=/sim_clock", "-r", "__ns:=/ns1", "-p", "state_rate:=10",
                    "--log-level", "info")
    try:
        out = sim.client("ros_args.py")
        log = sim.output()
    finally:
        sim.stop()
    topics, services = set(out["topics"]), set(out["services"])
    assert "/sim_clock" in topics and "/clock" not in topics
    assert "/ns1/bot_get_obj_position" in services and "/bot_get_obj_position" not in services
    assert "/ns1/bot_setWheelVelocity" in topics and "/bot/odom" in topics and "/get_entities" in services
    assert "/ns1/sigcore" in out["nodes"] and "/ns1/sigcore_actions" in out["nodes"], out["nodes"]
    gaps = [round(b - a, 6) for a, b in zip(out["odom"], out["odom"][1:], strict=False)]
    assert len(gaps) >= 4 and set(gaps) == {0.1}, gaps
    assert "ROS 2 transport ready" in log  # --log-level info: the sigcore loggers' INFO lines appear


def _run(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "sigcore", "run", str(WORLD), "-q", "--duration", "0.01", *args],
                          env=ros_env(), capture_output=True, text=True, timeout=120)


@pytest.mark.parametrize(("args", "message"), [
    (["-p", "state_rte:=10"], "-p state_rte: unknown parameter; valid: clock_rate, "),
    (["-p", "state_rate:=fast"], "-p state_rate:=fast: 'fast' is not a number; valid: a number, state_rate > 0 [Hz]"),
    (["-p", "use_sim_time:=false"], "use_sim_time is always true"),
    (["-p", "sigros_agents:=robots nobody"], "'nobody' is no agent, kind or tag of this world; valid: auto, all"),
    (["--params-file", "x.yaml"], "unknown argument '--params-file'; valid: -r/--remap FROM:=TO, -p/--param"),
    (["-r", "clock"], "-r 'clock' is not FROM:=TO"),
    (["--log-level", "loud"], "unknown level 'loud'; valid: debug, info, warn, error, fatal"),
])
def test_bad_ros_args_are_refused_before_anything_starts(args: list[str], message: str) -> None:
    """A bad parameter or an unknown argument after --ros-args exits 2 with a line naming it and what is valid."""
    done = _run("--ros-args", *args)
    assert done.returncode == 2, done.stderr
    assert message in done.stderr, done.stderr
    assert "Traceback" not in done.stderr


def test_ros_args_without_a_transport_is_refused() -> None:
    """--ros-args with --transport none exits 2 and says why."""
    done = _run("--transport", "none", "--ros-args", "-r", "/clock:=/c")
    assert done.returncode == 2 and "--transport none has no transport to take them" in done.stderr, done.stderr


def test_arguments_after_double_dash_are_sigcores_again() -> None:
    """'--ros-args ... --' ends the transport's arguments: what follows is parsed by sigcore run."""
    done = _run("--ros-args", "-p", "state_rate:=10", "--", "--wait-for", "/nope")
    assert done.returncode == 2 and "--wait-for /nope: not a topic" in done.stderr, done.stderr
