"""sig_ros-compatible services of robot_000 (SI units, z up); an unknown name gets an error, not a crash."""

import rclpy
from _ready import wait_ready
from sigcore_msgs.srv import GetEntities, GetJointAngle, GetObjPosition


def call(node, srv_type, name, /, **fields):
    client = node.create_client(srv_type, name)
    client.wait_for_service(timeout_sec=10.0)
    future = client.call_async(srv_type.Request(**fields))
    rclpy.spin_until_future_complete(node, future, timeout_sec=10.0)
    return future.result()


def main() -> None:
    rclpy.init()
    node = rclpy.create_node("sigros_queries")
    wait_ready(node)
    print("entities:", call(node, GetEntities, "/robot_000_get_entities").entities_names)
    can = call(node, GetObjPosition, "/robot_000_get_obj_position", name="can_0")
    print(f"can_0 at ({can.pos_x:.3f}, {can.pos_y:.3f}, {can.pos_z:.3f}) m")
    me = call(node, GetObjPosition, "/robot_000_get_obj_position", name="")  # "" = this agent
    print(f"robot_000 at ({me.pos_x:.3f}, {me.pos_y:.3f}) m")
    joint = call(node, GetJointAngle, "/robot_000_get_joint_angle", name="", name_arm="wheel_l_joint")
    print(f"wheel_l_joint: {joint.angle:.3f} rad")
    bad = call(node, GetObjPosition, "/robot_000_get_obj_position", name="no_such_thing")
    print(f"unknown entity -> success={bad.success}: {bad.message}")
    node.destroy_node()
    rclpy.shutdown()


if __name__ == "__main__":
    main()
