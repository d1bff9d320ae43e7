"""CdrTemplate: patched serialized messages equal the rmw's serialization of the same messages."""

from __future__ import annotations

import random

import pytest

pytest.importorskip("rclpy", reason="rclpy (ROS 2 Jazzy wheels) is not importable")

from geometry_msgs.msg import TransformStamped  # noqa: E402
from nav_msgs.msg import Odometry  # noqa: E402
from rclpy.serialization import deserialize_message, serialize_message  # noqa: E402
from rosgraph_msgs.msg import Clock  # noqa: E402
from sensor_msgs.msg import JointState  # noqa: E402
from sigcore_ros2.cdr import CdrTemplate  # noqa: E402
from tf2_msgs.msg import TFMessage  # noqa: E402


def test_clock_bytes_equal_the_rmw_serialization() -> None:
    """A patched Clock is byte for byte what rclpy serializes for a Clock with those values."""
    template = CdrTemplate(Clock(), ["clock.sec", "clock.nanosec"])
    for sec, nanosec in ((0, 0), (1, 2_000_000), (123456, 999_999_999)):
        msg = Clock()
        msg.clock.sec, msg.clock.nanosec = sec, nanosec
        assert template.pack(sec, nanosec) == serialize_message(msg)


def test_odometry_tf_and_joint_states_round_trip() -> None:
    """Random values written into Odometry, a two-transform TFMessage and a JointState templates deserialize to
    messages holding exactly those values, with frame ids and names unchanged."""
    rng = random.Random(1)
    odom = Odometry()
    odom.header.frame_id, odom.child_frame_id = "odom", "base_link"
    fields = ["header.stamp.sec", "header.stamp.nanosec", "pose.pose.position.x", "pose.pose.position.y",
              "pose.pose.orientation.z", "pose.pose.orientation.w", "twist.twist.linear.x", "twist.twist.angular.z"]
    template = CdrTemplate(odom, fields)
    values = [7, 500_000_000] + [rng.uniform(-5, 5) for _ in range(6)]
    out = deserialize_message(template.pack(*values), Odometry)
    assert (out.header.frame_id, out.child_frame_id) == ("odom", "base_link")
    assert (out.header.stamp.sec, out.header.stamp.nanosec) == (7, 500_000_000)
    assert [out.pose.pose.position.x, out.pose.pose.position.y, out.pose.pose.orientation.z,
            out.pose.pose.orientation.w, out.twist.twist.linear.x, out.twist.twist.angular.z] == values[2:]
    assert out.pose.pose.position.z == 0.0 and out.pose.covariance.tolist() == [0.0] * 36

    tf = TFMessage(transforms=[TransformStamped(), TransformStamped()])
    for t, (parent, child) in zip(tf.transforms, (("a/odom", "a/base"), ("b/odom", "b/base")), strict=True):
        t.header.frame_id, t.child_frame_id = parent, child
    names = ("header.stamp.sec", "header.stamp.nanosec", "transform.translation.x", "transform.rotation.w")
    template = CdrTemplate(tf, [f"transforms.{i}.{n}" for i in range(2) for n in names])
    out = deserialize_message(template.pack(1, 2, 0.5, 0.25, 3, 4, -1.5, 1.0), TFMessage)
    assert [t.child_frame_id for t in out.transforms] == ["a/base", "b/base"]
    assert out.transforms[1].header.stamp.sec == 3 and out.transforms[1].transform.translation.x == -1.5
    assert out.transforms[0].transform.rotation.w == 0.25

    js = JointState()
    js.name = ["j1", "j2", "j3"]
    js.position, js.velocity = [0.0] * 3, [0.0] * 3
    template = CdrTemplate(js, ["header.stamp.sec", "header.stamp.nanosec", "position", "velocity"])
    assert template.size == 8
    out = deserialize_message(template.pack(5, 6, 0.1, 0.2, 0.3, -1.0, -2.0, -3.0), JointState)
    assert list(out.name) == ["j1", "j2", "j3"]
    assert list(out.position) == [0.1, 0.2, 0.3] and list(out.velocity) == [-1.0, -2.0, -3.0]


def test_non_numeric_field_is_refused() -> None:
    """A template over a string field is refused with the field's path and type."""
    with pytest.raises(ValueError, match="header.frame_id: string is not a numeric field"):
        CdrTemplate(Odometry(), ["header.frame_id"])
