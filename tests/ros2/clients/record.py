"""In lockstep (the simulation was started paused with --record): subscribe to /bot/joint_states and /tf with
deep reliable queues; drive the robot (cmd_vel), step 10 x 50 steps through step_simulation, with a new cmd_vel
after the 3rd call, a sig_ros joint command after the 4th, a full reset_simulation after the 6th, a box spawned
above the ball after the 7th (it knocks the ball away), the cube deleted and the heavy box's information set after
the 8th; let the last messages arrive, and report the stamps received [ns] and the services' results."""

from common import Client, emit
from geometry_msgs.msg import Twist
from rclpy.qos import QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import JointState
from sigcore_msgs.msg import SetJointAngle
from simulation_interfaces.msg import EntityCategory
from simulation_interfaces.srv import DeleteEntity, ResetSimulation, SetEntityInfo, SpawnEntity, StepSimulation
from tf2_msgs.msg import TFMessage

c = Client("record_probe")
deep = QoSProfile(depth=5000, reliability=ReliabilityPolicy.RELIABLE)
joints = c.listen(JointState, "/bot/joint_states", deep)
tf = c.listen(TFMessage, "/tf", deep)
c.wait_for(lambda: c.node.count_publishers("/bot/joint_states") > 0 and c.node.count_publishers("/tf") > 0, 30.0)
c.spin(1.0)
c.publish(Twist, "/bot/cmd_vel", **{"linear.x": 0.4, "angular.z": 0.6})
# a topic and a service are not ordered: the first step request must not overtake the first command (it did in a
# ci-fresh run with four test workers, and the command took effect at step 1); 1 s is ten times the wait between the
# later commands and the steps after them
c.spin(1.0)
results, resets, changes = [], [], {}
for i in range(10):
    results.append(c.call(StepSimulation, "/step_simulation", timeout=60.0, steps=50).result.result)
    if i == 2:
        c.publish(Twist, "/bot/cmd_vel", **{"linear.x": -0.2, "angular.z": -1.0})
    if i == 3:
        c.publish(SetJointAngle, "bot_setJointTarget", joint_name="shoulder_joint", angle=0.7)
    if i == 5:
        resets.append(c.call(ResetSimulation, "/reset_simulation").result.result)
    if i == 6:
        got = c.call(SpawnEntity, "/spawn_entity", timeout=30.0, name="crate",
                     resource_string='<object shape="box" size="0.1 0.1 0.1" mass="1"/>',
                     **{"initial_pose.pose.position.x": -0.96, "initial_pose.pose.position.y": 1.0,
                        "initial_pose.pose.position.z": 0.3, "initial_pose.pose.orientation.w": 1.0})
        changes["spawn"] = [got.result.result, got.entity_name]
    if i == 7:
        changes["delete"] = c.call(DeleteEntity, "/delete_entity", timeout=30.0, entity="cube").result.result
        changes["info"] = c.call(SetEntityInfo, "/set_entity_info", entity="heavy", **{
            "info.category.category": EntityCategory.CATEGORY_DYNAMIC_OBJECT, "info.description": "pushed",
            "info.tags": ["furniture", "moved"]}).result.result
    c.spin(0.1)  # the commands reach the simulation before the next steps


def ns(stamp) -> int:
    return stamp.sec * 1_000_000_000 + stamp.nanosec


c.wait_for(lambda: bool(joints) and ns(joints[-1].header.stamp) >= 500 * 2_000_000, 20.0)
c.spin(0.5)
emit({"results": results, "resets": resets, "changes": changes, "joints": [ns(m.header.stamp) for m in joints],
      "tf": [[ns(t.header.stamp) for t in m.transforms][:1] for m in tf]})
