"""Drive robot_000 forward for 2 s of simulated time with cmd_vel; print odometry and the nearest obstacle."""

import math

import rclpy
from _ready import wait_ready
from geometry_msgs.msg import Twist
from nav_msgs.msg import Odometry
from rclpy.qos import qos_profile_sensor_data
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import LaserScan


def main() -> None:
    rclpy.init()
    node = rclpy.create_node("drive_example")
    wait_ready(node)
    latest = {}
    node.create_subscription(Odometry, "/robot_000/odom", lambda m: latest.update(odom=m), 10)
    node.create_subscription(LaserScan, "/robot_000/base_scan", lambda m: latest.update(scan=m),
                             qos_profile_sensor_data)  # REP-2003: consumers use SensorDataQoS
    node.create_subscription(Clock, "/clock", lambda m: latest.update(clock=m.clock), 10)
    cmd = node.create_publisher(Twist, "/robot_000/cmd_vel", 10)
    while "clock" not in latest or "odom" not in latest:
        rclpy.spin_once(node, timeout_sec=0.1)

    def now() -> float:
        return latest["clock"].sec + latest["clock"].nanosec * 1e-9

    start = now()
    twist = Twist()
    twist.linear.x = 0.3
    while now() - start < 2.0:  # simulated seconds: works at any real-time factor
        cmd.publish(twist)
        rclpy.spin_once(node, timeout_sec=0.05)
    cmd.publish(Twist())
    odom = latest["odom"].pose.pose
    yaw = 2 * math.atan2(odom.orientation.z, odom.orientation.w)
    print(f"odom: x={odom.position.x:.3f} m y={odom.position.y:.3f} m yaw={yaw:.3f} rad at t={now():.3f} s")
    if "scan" in latest:
        ranges = [r for r in latest["scan"].ranges if math.isfinite(r)]
        print(f"nearest obstacle: {min(ranges):.2f} m ({len(latest['scan'].ranges)} beams)")
    node.destroy_node()
    rclpy.shutdown()


if __name__ == "__main__":
    main()
