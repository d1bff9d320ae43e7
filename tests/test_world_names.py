"""ROS naming rules in the core (sigcore.world.names) against rclpy's validators, and the endpoint plan check."""

from __future__ import annotations

from pathlib import Path

import pytest

from sigcore.sim import Simulation
from sigcore.transport import Endpoint, Transport
from sigcore.world import parse_world
from sigcore.world.models import valid_name
from sigcore.world.names import MAX_NAME_LENGTH, full_name_problem, plan_issues, token_problem

rclpy_topic = pytest.importorskip("rclpy.validate_topic_name")
rclpy_full = pytest.importorskip("rclpy.validate_full_topic_name")

SIGBOT = Path(__file__).resolve().parents[1] / "worlds" / "models" / "sigbot" / "sigbot.urdf"

TRICKY = ["a", "A", "_", "_a", "a_", "a__b", "__a", "a1", "1a", "9", "", "a-b", "a b", "a.b", "a/b", "/a", "a/",
          "~", "~a", "{a}", "a{b}", "ä", "robotä", "a\tb", "a\nb", "ａ", "a" * 64, "a" * 65, "a" * 300, "a:b", "a*",
          "$a", "a@b", "robot_000", "Robot_000", "sigcore", "odom", "cmd_vel", "%s"]
"""Names people and fuzzers write: separators, digits, unicode look-alikes, ROS substitutions, lengths."""

FULL = ["/", "//", "/a", "/a/", "/a//b", "/a/b", "/a/1b", "/1a", "a", "/a b", "/a-b", "/_a/_b", "/a__b", "/~",
        "/a/~", "/{a}", "/ä", "/" + "a" * (MAX_NAME_LENGTH - 1), "/" + "a" * MAX_NAME_LENGTH,
        "/" + "/".join(["ab"] * 100), "/robot_000/odom", "/sigcore/ready", "/a/b/c_d/E9"]
"""Full names: separators, empty tokens, lengths around rmw's limit."""


def _rclpy_accepts(validate: object, name: str) -> bool:
    try:
        validate(name)  # type: ignore[operator]
    except Exception:  # InvalidTopicNameException, or rcl refusing a NUL / non-ASCII name
        return False
    return True


@pytest.mark.parametrize("name", [n for n in TRICKY if "/" not in n and len(n) < 200])
def test_token_rule_matches_rclpy(name: str) -> None:
    """A token (no '/', short) is valid for the core exactly when rclpy accepts it as the last token of a full
    topic name."""
    assert (token_problem(name) is None) == _rclpy_accepts(rclpy_full.validate_full_topic_name, "/x/" + name)


@pytest.mark.parametrize("name", FULL)
def test_full_name_rule_matches_rclpy(name: str) -> None:
    """A full name is valid for the core exactly when rclpy's validate_full_topic_name accepts it."""
    assert (full_name_problem(name) is None) == _rclpy_accepts(rclpy_full.validate_full_topic_name, name)


@pytest.mark.parametrize("name", TRICKY)
def test_world_names_are_valid_ros_tokens(name: str) -> None:
    """Every name the world format accepts is a valid ROS token, alone and as an agent's endpoint prefix."""
    if valid_name(name) and len(name) <= 64:
        assert token_problem(name) is None
        assert _rclpy_accepts(rclpy_topic.validate_topic_name, name + "_setWheel")
        assert _rclpy_accepts(rclpy_full.validate_full_topic_name, f"/{name}/{name}")


@pytest.mark.parametrize("name", ["a/b", "a\x00b", "/a\x00"])
def test_separators_and_nul_are_refused(name: str) -> None:
    """A '/' is no part of a token, and a NUL (which rcl would silently cut the name at) no part of any name."""
    assert token_problem(name) is not None
    if "\x00" in name:
        assert full_name_problem("/" + name.lstrip("/")) is not None


def _world(tmp_path: Path, body: str) -> Simulation:
    path = tmp_path / "w.xml"
    path.write_text(f'<world name="w">\n  <robot name="r" urdf="{SIGBOT}">\n'
                    '    <drive type="differential" left="wheel_l_joint" right="wheel_r_joint" radius="0.1" '
                    f'separation="0.4"/>\n    {body}\n  </robot>\n</world>\n')
    return Simulation(parse_world(path), "mujoco")


class _Plain(Transport):
    name = "plain"

    def start(self, sim: Simulation) -> None:
        """Nothing to start."""

    def service(self, timeout: float) -> None:
        """Nothing to serve."""

    def stop(self) -> None:
        """Nothing to stop."""


def test_collision_is_located_at_the_element_and_names_both_uses(tmp_path: Path) -> None:
    """Two endpoints with one name are one issue at the element that brought the later in, naming both."""
    sim = _world(tmp_path, '<lidar name="scan" link="base_laser_link"/>')
    plan = [Endpoint("/r/odom", "nav_msgs/msg/Odometry", "topic", "the odometry", "r", "drive", "drive"),
            Endpoint("/r/odom", "sensor_msgs/msg/LaserScan", "topic", "the scans", "r", "lidar:scan", "lidar")]
    issues = plan_issues(sim.world, plan, "test")
    assert len(issues) == 1
    assert (issues[0].line, issues[0].element) == (4, "lidar")
    assert "the scans" in issues[0].message and "the odometry" in issues[0].message


def test_topic_and_service_may_share_a_name_and_tf_is_shared(tmp_path: Path) -> None:
    """A topic and a service of one name, and two /tf publishers of one type, are no collision."""
    sim = _world(tmp_path, "")
    plan = [Endpoint("/a", "std_msgs/msg/Bool", "topic", "x"), Endpoint("/a", "std_srvs/srv/Empty", "service", "y"),
            Endpoint("/tf", "tf2_msgs/msg/TFMessage", "topic", "odometry", shared=True),
            Endpoint("/tf", "tf2_msgs/msg/TFMessage", "topic", "slam", shared=True)]
    assert plan_issues(sim.world, plan, "test") == []


def test_invalid_full_name_is_an_issue(tmp_path: Path) -> None:
    """An endpoint whose full name breaks the ROS rule is an issue naming the rule."""
    sim = _world(tmp_path, "")
    issues = plan_issues(sim.world, [Endpoint("/" + "a" * 300, "std_msgs/msg/Bool", "topic", "x", "r", "name")],
                         "test")
    assert len(issues) == 1 and f"at most {MAX_NAME_LENGTH} characters" in issues[0].message


def test_default_plan_derives_describe(tmp_path: Path) -> None:
    """The base transport's describe lists exactly the names and types of its plan, and the plan checks clean."""
    sim = _world(tmp_path, '<lidar name="scan" link="base_laser_link"/>')
    transport = _Plain()
    plan = transport.plan(sim)
    assert transport.describe(sim) == {e.name: e.type for e in plan}
    assert any(e.agent == "r" for e in plan)
    assert transport.check(sim) == []


@pytest.mark.parametrize("topic", ["odom", "cmd_vel", "joint_states"])
def test_ros2_plan_finds_lidar_named_like_a_standard_topic(tmp_path: Path, topic: str) -> None:
    """The ROS 2 transport's check refuses a lidar named like the robot's standard topics, at the lidar."""
    transport_module = pytest.importorskip("sigcore_ros2.transport")
    sim = _world(tmp_path, f'<lidar name="{topic}" link="base_laser_link"/>')
    issues = transport_module.Ros2Transport().check(sim)  # starts no ROS 2 nodes
    assert len(issues) == 1
    assert issues[0].line == 4 and f"'/r/{topic}'" in issues[0].message
