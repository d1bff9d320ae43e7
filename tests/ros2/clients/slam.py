"""Listen to SLAM over ROS 2: /map (latched OccupancyGrid), map -> odom on /tf, the SLAM pose, world -> map on
/tf_static; drive a little with cmd_vel so the map grows."""

from common import Client, emit
from geometry_msgs.msg import PoseStamped, Twist
from nav_msgs.msg import OccupancyGrid
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from tf2_msgs.msg import TFMessage

c = Client("slam_probe")
c.wait_ready()
latched = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL)
maps = c.listen(OccupancyGrid, "/map", latched)
static = c.listen(TFMessage, "/tf_static", latched)
tfs = c.listen(TFMessage, "/tf")
poses = c.listen(PoseStamped, "/robot_000/slam_pose")
for _ in range(10):
    c.publish(Twist, "/robot_000/cmd_vel", **{"linear.x": 0.3})
    c.spin(0.1)
c.publish(Twist, "/robot_000/cmd_vel", **{"linear.x": 0.0})
c.wait_for(lambda: len(maps) >= 2 and poses and static, 15.0)


def stamp(h):
    return h.stamp.sec + h.stamp.nanosec * 1e-9


m2o = [t for m in tfs for t in m.transforms if t.header.frame_id == "map" and t.child_frame_id == "odom"]
grid = maps[-1] if maps else None
emit({
    "maps": len(maps),
    "map_frame": grid.header.frame_id if grid else None,
    "map_info": [grid.info.width, grid.info.height, grid.info.resolution] if grid else None,
    "map_values": sorted({int(v) for v in grid.data}) if grid else [],
    "static_pairs": [[t.header.frame_id, t.child_frame_id] for m in static for t in m.transforms],
    "map_to_odom": len(m2o),
    "m2o_stamps": [stamp(t.header) for t in m2o[-5:]],
    "pose_frame": poses[-1].header.frame_id if poses else None,
    "pose_x": poses[-1].pose.position.x if poses else None,
})
