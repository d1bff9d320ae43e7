"""``sigcore ros call SERVICE YAML``: one service call from one hidden node, the request filled from a YAML mapping
with every field checked, the response printed as YAML."""

from __future__ import annotations

import sys
import time
from typing import Annotated

import typer

from ..exceptions import RosToolError
from .console import command_errors
from .graph import DISCOVERY_WAIT, Graph, domain, full_name, listing
from .messages import checked, fill, interface_class
from .yamltext import YamlStyle, parse_request, to_yaml


def call_command(
    service: Annotated[str, typer.Argument(help="the service, e.g. /sigcore/set_flag")],
    request: Annotated[str, typer.Argument(help="the request's fields as a YAML mapping, e.g. '{data: true}' or "
                                           "'{pose: {position: {x: 1.0}}}'")] = "{}",
    timeout: Annotated[float, typer.Option("--timeout", min=0, help="wait this long for the response (seconds) "
                                           "(exit 1 without one)")] = 5.0,
    wait: Annotated[float, typer.Option("--wait", min=0, help="how long the service may take to appear on the "
                                        "graph (seconds)")] = DISCOVERY_WAIT,
) -> None:
    """Call a service once and print its response as YAML. The type comes from the graph; the request is filled
    from the YAML mapping (fields not given keep their defaults). Where ROS 2 is installed, `ros2 service call`
    does the same."""
    with command_errors("call"):
        service = full_name(service, service=True)
        values = parse_request(request)
        with Graph("call") as graph:
            stop = graph.stop
            types, found = graph.wait_for(graph.services, service, wait)
            if types is None:
                raise RosToolError(f"service {service} is not on the ROS 2 graph ({domain()}, after {wait:g} s)"
                                   f"{listing(service, found, 'services')}")
            if len(types) != 1:
                raise RosToolError(f"service {service} has several types ({', '.join(types)}); cannot choose one")
            cls = interface_class(types[0], "srv")
            message = fill(checked(cls.Request), values, "request")
            client = graph.node.create_client(cls, service)
            start = time.monotonic()
            while not client.service_is_ready():
                if stop.now:
                    raise typer.Exit(1)
                if time.monotonic() - start >= timeout:
                    raise RosToolError(f"the server of {service} did not answer discovery within {timeout:g} s", 1)
                graph.spin(0.05)
            future = client.call_async(message)
            while not future.done():
                if stop.now:
                    raise typer.Exit(1)
                if time.monotonic() - start >= timeout:
                    raise RosToolError(f"no response from {service} within {timeout:g} s", 1)
                graph.executor.spin_once(timeout_sec=0.05)
            sys.stdout.write(to_yaml(future.result(), YamlStyle(truncate=0)))
            sys.stdout.flush()
