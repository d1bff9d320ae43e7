"""The registration of the ROS 2 plugin's commands with the ``sigcore`` typer app (``sigcore_register_commands``):
the ``sigcore ros`` group (:data:`ros_app`) and ``play`` in the ``bag`` group (:mod:`.play`).

``sigcore ros``: ROS 2 introspection for users who installed sigcore with pip and have no ``ros2`` command. Thin
wrappers over rclpy, each in one short-lived hidden node (``_sigcore_ros_<command>_<pid>``, no ``/rosout``, no
parameter services; its own endpoints are left out of every list and count):

- ``sigcore ros topics``: the topics on the graph, with their types and publisher / subscriber counts;
- ``sigcore ros echo TOPIC``: messages as YAML, ``---`` between them;
- ``sigcore ros hz TOPIC``: the rate of a topic (raw subscription: nothing is deserialized);
- ``sigcore ros call SERVICE YAML``: one service call, the response as YAML;
- ``sigcore ros record DIR``: a rosbag2 directory (MCAP) of topics received over DDS, written by
  :class:`sigcore.record.bag.BagWriter` with the bytes as they came.

DDS discovery is asynchronous: every command first waits (``--wait``) for the graph to show what it needs. Bad input
(an unknown topic or service, a type that cannot be imported, malformed YAML, an unknown field) ends the command with
one line on stderr and exit status 2; a timeout or a topic that stays silent with exit status 1. Where ROS 2 is
installed, the real ``ros2 topic list / echo / hz``, ``ros2 service call`` and ``ros2 bag record`` do the same.
See ``docs/ros-tools.md``.
"""

from __future__ import annotations

from typing import Any

import typer

from .call import call_command
from .record import record_command
from .topics import echo_command, hz_command, topics_command

ros_app = typer.Typer(help="ROS 2 introspection without a ROS install: topics, echo, hz, call, record. Where ROS 2 is "
                      "installed, the real ros2 CLI does the same.", no_args_is_help=True,
                      rich_markup_mode=None)
ros_app.command("topics")(topics_command)
ros_app.command("echo")(echo_command)
ros_app.command("hz")(hz_command)
ros_app.command("call")(call_command)
ros_app.command("record")(record_command)


def register(cli: Any) -> None:
    """Add ``ros`` (a group) to ``cli`` and ``play`` to its ``bag`` group."""
    cli.add_typer(ros_app, name="ros")
    bag = next((g.typer_instance for g in cli.registered_groups if g.name == "bag"), None)
    if bag is not None:
        from .play import play_command

        bag.command(name="play")(play_command)
