"""The ROS 2 plugin's command-line commands: ``sigcore ros ...`` (:mod:`.tools`) and ``sigcore bag play``
(:mod:`.play`), added to the ``sigcore`` typer app through ``sigcore_register_commands``."""

from __future__ import annotations

from typing import Any


def register(cli: Any) -> None:
    """Add ``ros`` (a group) to ``cli`` and ``play`` to its ``bag`` group."""
    from .tools import ros_app

    cli.add_typer(ros_app, name="ros")
    bag = next((g.typer_instance for g in cli.registered_groups if g.name == "bag"), None)
    if bag is not None:
        from .play import play_command

        bag.command(name="play")(play_command)
