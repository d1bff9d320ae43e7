"""Launch sigcore for users with ROS 2 installed: a thin wrapper of the ``sigcore run`` command.

    ros2 launch launch/sigcore.launch.py world:=worlds/cleanup.xml
    ros2 launch launch/sigcore.launch.py world:=worlds/cleanup.xml backend:=bullet paused:=true \\
        extra_args:="--factor 2 --wait-for /robot_000/cmd_vel --ros-args -r __ns:=/sim"

Launch arguments: ``world`` (the world file, required), ``backend`` (``mujoco``), ``paused`` (``false``; true:
wait for ``set_simulation_state`` PLAYING) and ``extra_args`` (more ``sigcore run`` options, split like a shell
command line). The command itself is :func:`sigcore_command`, a plain function that the tests run without ROS 2's
``launch`` package (which is imported only inside :func:`generate_launch_description`).
"""

from __future__ import annotations

import shlex
from typing import Any

TRUE = ("true", "1", "yes", "on")
FALSE = ("false", "0", "no", "off", "")


def sigcore_command(world: str, backend: str = "mujoco", paused: str = "false", extra_args: str = "",
                    executable: str = "sigcore") -> list[str]:
    """The ``sigcore run`` command line for the launch arguments.

    Args:
        world: The world file.
        backend: The physics backend (``mujoco``, ``bullet``).
        paused: ``true`` or ``false`` (launch arguments are text).
        extra_args: More ``sigcore run`` options, split like a shell command line (``--ros-args ...`` included).
        executable: The ``sigcore`` command (found on ``PATH`` by default).

    Raises:
        ValueError: ``world`` is empty or ``paused`` is not a boolean word.
    """
    if not world:
        raise ValueError("the launch argument 'world' is required, e.g. world:=worlds/cleanup.xml")
    if paused.lower() not in TRUE + FALSE:
        raise ValueError(f"paused:={paused!r} is not a boolean; valid: true, false")
    cmd = [executable, "run", world, "--backend", backend]
    if paused.lower() in TRUE:
        cmd.append("--paused")
    return cmd + shlex.split(extra_args)


def generate_launch_description() -> Any:
    """The launch description: the four arguments and one ExecuteProcess of :func:`sigcore_command`."""
    from launch.actions import DeclareLaunchArgument, ExecuteProcess, OpaqueFunction
    from launch.substitutions import LaunchConfiguration

    from launch import LaunchDescription

    def process(context: Any) -> list[Any]:
        def arg(name: str) -> str:
            return str(LaunchConfiguration(name).perform(context))

        cmd = sigcore_command(arg("world"), arg("backend"), arg("paused"), arg("extra_args"))
        return [ExecuteProcess(cmd=cmd, output="screen", sigterm_timeout="10")]

    return LaunchDescription([
        DeclareLaunchArgument("world", description="the world file (e.g. worlds/cleanup.xml)"),
        DeclareLaunchArgument("backend", default_value="mujoco", description="physics backend: mujoco or bullet"),
        DeclareLaunchArgument("paused", default_value="false",
                              description="start paused until set_simulation_state PLAYING"),
        DeclareLaunchArgument("extra_args", default_value="",
                              description="more sigcore run options, e.g. '--factor 2 --ros-args -r __ns:=/sim'"),
        OpaqueFunction(function=process),
    ])
