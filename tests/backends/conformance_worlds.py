"""The bot URDF, world snippets and helpers shared by the backend conformance suite (any registered backend)."""

from __future__ import annotations

from sigcore.backend import Backend

G = 9.81

BOT_URDF = """<?xml version="1.0"?>
<!-- Differential drive: wheels r = 0.1 m, 0.4 m apart, on the base's y axis; frictionless casters front and
back;
     a 2-joint arm (pitch about y) at x = -0.1 ending in a hand link; a lidar link 0.25 m above the base
     frame. -->
<robot name="bot">
  <link name="base_link">
    <inertial><origin xyz="0 0 0.1"/><mass value="10"/>
      <inertia ixx="0.1" ixy="0" ixz="0" iyy="0.15" iyz="0" izz="0.2"/></inertial>
    <visual><geometry><mesh filename="package://bot/meshes/base.dae"/></geometry></visual>
    <collision><origin xyz="0 0 0.1"/><geometry><box size="0.4 0.3 0.1"/></geometry></collision>
  </link>
  <link name="wheel_l">
    <inertial><mass value="0.5"/><inertia ixx="0.0013" ixy="0" ixz="0" iyy="0.0025" iyz="0"
    izz="0.0013"/></inertial> <collision><origin rpy="1.5708 0 0"/><geometry><cylinder radius="0.1"
    length="0.04"/></geometry></collision>
  </link>
  <joint name="wheel_l_joint" type="continuous">
    <parent link="base_link"/><child link="wheel_l"/><origin xyz="0 0.2 0.1"/><axis xyz="0 1 0"/>
  </joint>
  <link name="wheel_r">
    <inertial><mass value="0.5"/><inertia ixx="0.0013" ixy="0" ixz="0" iyy="0.0025" iyz="0"
    izz="0.0013"/></inertial> <collision><origin rpy="1.5708 0 0"/><geometry><cylinder radius="0.1"
    length="0.04"/></geometry></collision>
  </link>
  <joint name="wheel_r_joint" type="continuous">
    <parent link="base_link"/><child link="wheel_r"/><origin xyz="0 -0.2 0.1"/><axis xyz="0 1 0"/>
  </joint>
  <link name="caster_f">
    <inertial><mass value="0.1"/><inertia ixx="0.0001" ixy="0" ixz="0" iyy="0.0001" iyz="0"
    izz="0.0001"/></inertial> <collision><geometry><sphere radius="0.05"/></geometry></collision>
  </link>
  <joint name="caster_f_joint" type="fixed">
    <parent link="base_link"/><child link="caster_f"/><origin xyz="0.15 0 0.05"/>
  </joint>
  <link name="caster_b">
    <inertial><mass value="0.1"/><inertia ixx="0.0001" ixy="0" ixz="0" iyy="0.0001" iyz="0"
    izz="0.0001"/></inertial> <collision><geometry><sphere radius="0.05"/></geometry></collision>
  </link>
  <joint name="caster_b_joint" type="fixed">
    <parent link="base_link"/><child link="caster_b"/><origin xyz="-0.15 0 0.05"/>
  </joint>
  <link name="lidar_link"/>
  <joint name="lidar_joint" type="fixed">
    <parent link="base_link"/><child link="lidar_link"/><origin xyz="0.1 0 0.25"/>
  </joint>
  <link name="arm_1">
    <inertial><origin xyz="0 0 0.15"/><mass value="0.5"/>
      <inertia ixx="0.004" ixy="0" ixz="0" iyy="0.004" iyz="0" izz="0.0002"/></inertial>
    <collision><origin xyz="0 0 0.15"/><geometry><cylinder radius="0.03" length="0.3"/></geometry></collision>
  </link>
  <joint name="shoulder" type="revolute">
    <parent link="base_link"/><child link="arm_1"/><origin xyz="-0.1 0 0.15"/><axis xyz="0 1 0"/>
    <limit lower="-2" upper="2" effort="50" velocity="2"/>
  </joint>
  <link name="arm_2">
    <inertial><origin xyz="0 0 0.125"/><mass value="0.3"/>
      <inertia ixx="0.002" ixy="0" ixz="0" iyy="0.002" iyz="0" izz="0.0001"/></inertial>
    <collision><origin xyz="0 0 0.125"/><geometry><cylinder radius="0.025"
    length="0.25"/></geometry></collision>
  </link>
  <joint name="elbow" type="revolute">
    <parent link="arm_1"/><child link="arm_2"/><origin xyz="0 0 0.3"/><axis xyz="0 1 0"/>
    <limit lower="-2.5" upper="2.5" effort="50" velocity="2"/>
  </joint>
  <link name="hand">
    <inertial><mass value="0.05"/><inertia ixx="0.00001" ixy="0" ixz="0" iyy="0.00001" iyz="0" izz="0.00001"/>
    </inertial>
    <collision><geometry><box size="0.04 0.04 0.04"/></geometry></collision>
  </link>
  <joint name="hand_joint" type="fixed">
    <parent link="arm_2"/><child link="hand"/><origin xyz="0 0 0.27"/>
  </joint>
  <gazebo reference="caster_f"><mu1>0.0</mu1><mu2>0.0</mu2></gazebo>
  <gazebo reference="caster_b"><mu1>0.0</mu1><mu2>0.0</mu2></gazebo>
</robot>
"""

ROBOT = """<robot name="bot" urdf="bot.urdf" pose="{pose}"{extra}>
    <drive left="wheel_l_joint" right="wheel_r_joint" radius="0.1" separation="0.4"/>
    <lidar name="scan" link="lidar_link"/>
    <gripper part="hand" grasp_radius="0.2"/>
  </robot>"""


def robot(pose: str = "0 0 0 0 0 0", extra: str = "") -> str:
    """The bot's ``<robot>`` element at ``pose``."""
    return ROBOT.format(pose=pose, extra=extra)


def run(backend: Backend, seconds: float, dt: float = 0.002) -> None:
    """Step ``backend`` for ``seconds`` of simulated time."""
    for _ in range(round(seconds / dt)):
        backend.step()


def turn_shoulder(backend: Backend) -> list[float]:
    """Turn the bot's shoulder at 0.5 rad/s (``set_joint_velocity``), let it settle for 0.5 s, and return its velocity
    after each of the next 250 steps (0.5 s)."""
    backend.set_joint_velocity("bot", "shoulder", 0.5)
    run(backend, 0.5)
    speeds = []
    for _ in range(250):
        backend.step()
        speeds.append(backend.get_joint_velocity("bot", "shoulder"))
    return speeds


def stop_shoulder(backend: Backend) -> float:
    """Set the bot's shoulder velocity to 0, let it settle for 0.5 s, and return its angle then."""
    backend.set_joint_velocity("bot", "shoulder", 0.0)
    run(backend, 0.5)
    return backend.get_joint_angle("bot", "shoulder")
