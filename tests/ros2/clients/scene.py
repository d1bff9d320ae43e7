"""Join late and read the latched /robot_description, /<robot>/robot_description and /sigcore/scene."""

import sys

from common import Client, emit
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from std_msgs.msg import String
from visualization_msgs.msg import MarkerArray

c = Client("scene_probe")
latched = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL)
topics = sys.argv[1:]
texts = {topic: c.listen(String, topic, latched) for topic in topics}
scenes = c.listen(MarkerArray, "/sigcore/scene", latched)
c.wait_for(lambda: scenes and all(texts.values()), 20.0)
markers = [{"ns": m.ns, "id": m.id, "type": m.type, "action": m.action, "frame": m.header.frame_id,
            "frame_locked": m.frame_locked, "scale": [m.scale.x, m.scale.y, m.scale.z],
            "color": [m.color.r, m.color.g, m.color.b, m.color.a], "mesh_resource": m.mesh_resource,
            "position": [m.pose.position.x, m.pose.position.y, m.pose.position.z]}
           for m in (scenes[-1].markers if scenes else [])]
emit({"texts": {topic: [m.data for m in got] for topic, got in texts.items()}, "scenes": len(scenes),
      "markers": markers})
