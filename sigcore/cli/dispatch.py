"""The ``sigcore`` typer app: every command registered in the order ``sigcore --help`` lists them (the ``bag`` group
among them, which plugins extend), and the console-script entry point that takes out the arguments after
``--ros-args``, loads the plugins (which add their own commands) and dispatches."""

from __future__ import annotations

import logging
import sys

import typer

from .. import plugins
from .common import err
from .eval import eval_command
from .info import api, check, interfaces, plugins_cmd, spawnables_cmd, worlds_cmd
from .replay import bag_info_command, replay
from .run import run
from .transport import TRANSPORT_ARGS, set_transport_args, split_transport_args
from .view import view

app = typer.Typer(help="sigcore: drive a physics simulation through ROS 2 topics and services.",
                  no_args_is_help=True, add_completion=False, pretty_exceptions_enable=False,
                  rich_markup_mode=None)  # help text is plain: units such as [s] stay as written
# Markup off: what is printed comes from users (names, errors, features' lines) and is never interpreted.

app.command()(run)
app.command()(view)
app.command()(check)
app.command()(api)
app.command()(interfaces)
app.command(name="plugins")(plugins_cmd)
app.command(name="spawnables")(spawnables_cmd)
app.command(name="worlds")(worlds_cmd)
app.command(name="eval")(eval_command)
app.command()(replay)

bag_app = typer.Typer(help="Recordings (rosbag2 directories with MCAP storage): look inside, play back.",
                      no_args_is_help=True, rich_markup_mode=None)
app.add_typer(bag_app, name="bag")
bag_app.command(name="info")(bag_info_command)


def main() -> None:
    """Console-script entry point. Arguments after ``--ros-args`` (up to an optional ``--``) are the transport's
    (``sigcore run`` only), taken out before typer parses the rest."""
    logging.basicConfig(level=logging.WARNING, format="%(levelname)s %(name)s: %(message)s")
    argv, transport_args = split_transport_args(sys.argv[1:])
    set_transport_args(transport_args)
    if transport_args is not None and (not argv or argv[0] != "run"):
        err.print(f"{TRANSPORT_ARGS} is taken by 'sigcore run' only (sigcore run WORLD [OPTIONS] {TRANSPORT_ARGS} "
                  "-r FROM:=TO -p NAME:=VALUE ...)", markup=False, soft_wrap=True)
        raise SystemExit(2)
    plugins.load_plugins()
    plugins.add_commands(app)
    app(args=argv)
