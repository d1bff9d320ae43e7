"""ROS naming rules, written in the core (no rclpy), and the check of a transport's endpoint plan.

World names (agents, lidars, arms, plugins) become parts of ROS names: ``robot_000_setWheel``, ``/robot_000/odom``,
``/robot_000/base_scan``. A name that is not a valid ROS name token, or an endpoint whose name another endpoint
already uses, makes the transport fail when it starts; :func:`plan_issues` finds both before, at the
``file:line:column`` of the element that brought the name in. ``tests/test_world_names.py`` compares
:func:`token_problem` and :func:`full_name_problem` with rclpy's validators.
"""

from __future__ import annotations

import re
from collections.abc import Callable, Iterable
from typing import TYPE_CHECKING

from .exceptions import WorldIssue

if TYPE_CHECKING:
    from ..transport import Endpoint
    from .models import World

MAX_NAME_LENGTH = 247
"""Longest full ROS topic name [characters]: rmw's limit, 255 minus the 8 of DDS's prefixes."""

_TOKEN = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")
_CHARS = re.compile(r"[A-Za-z0-9_/]*")


def token_problem(token: str) -> str | None:
    """Why ``token`` is not a valid ROS name token (one ``/``-separated part of a name), or None if it is.

    The rule of rcl's ``rcl_validate_topic_name`` for a token: not empty, only ASCII letters, digits and ``_``,
    not starting with a digit.
    """
    if not token:
        return "a ROS name token must not be empty"
    if _TOKEN.fullmatch(token):
        return None
    if token[0].isdigit():
        return "a ROS name token must not start with a digit"
    bad = next(c for c in token if not (c.isascii() and (c.isalnum() or c == "_")))
    return f"a ROS name token holds only ASCII letters, digits and '_' (not {bad!r})"


def full_name_problem(name: str) -> str | None:
    """Why ``name`` is not a valid fully qualified ROS topic or service name, or None if it is.

    The rule of rclpy's ``validate_full_topic_name``: starts with ``/``, does not end with ``/``, no ``//``, only
    ASCII letters, digits, ``_`` and ``/``, no token starting with a digit, at most :data:`MAX_NAME_LENGTH`
    characters. Stricter in one point: a NUL, at which rcl would silently cut the name, is refused.
    """
    if not name:
        return "a ROS name must not be empty"
    if not name.startswith("/"):
        return "a full ROS name starts with '/'"
    if not _CHARS.fullmatch(name):
        bad = next(c for c in name if not (c.isascii() and (c.isalnum() or c in "_/")))
        return f"a ROS name holds only ASCII letters, digits, '_' and '/' (not {bad!r})"
    if name.endswith("/"):
        return "a ROS name must not end with '/'"
    if "//" in name:
        return "a ROS name must not contain '//'"
    if any(token[0].isdigit() for token in name[1:].split("/")):
        return "a ROS name token must not start with a digit"
    if len(name) > MAX_NAME_LENGTH:
        return f"a ROS name has at most {MAX_NAME_LENGTH} characters (this one has {len(name)})"
    return None


def plan_issues(world: World, plan: Iterable[Endpoint], transport: str,
                name_problem: Callable[[str], str | None] = full_name_problem) -> list[WorldIssue]:
    """Every endpoint of ``plan`` whose name is invalid or used twice, as located world-file issues.

    Two endpoints collide when they have the same full name and are both topics, or both services, or both
    actions (ROS keeps topics and services apart), unless both are publishers of one type on a shared topic
    (``/tf``). Each issue is at the element that brought the later name in (the earlier one's if the later is the
    transport's own) and names both uses.

    Args:
        world: The world the plan was made for (for locations).
        plan: The transport's endpoints (:meth:`sigcore.transport.Transport.plan`).
        transport: The transport's name, for messages.
        name_problem: The rule a full name must follow (a transport may pass its middleware's own validator).

    Returns:
        The issues, sorted by line; empty when the plan can be created.
    """
    issues: list[WorldIssue] = []
    first: dict[tuple[str, str], Endpoint] = {}
    for endpoint in plan:
        full = endpoint.full_name
        problem = name_problem(full)
        if problem is not None:
            issues.append(_issue(world, endpoint, f"{endpoint.what} would be named {full!r}, which transport "
                                                  f"'{transport}' cannot create: {problem}"))
            continue
        key = (endpoint.kind, full)
        old = first.get(key)
        if old is None:
            first[key] = endpoint
            continue
        if old.shared and endpoint.shared and old.type == endpoint.type:
            continue
        blame = endpoint if endpoint.agent is not None or endpoint.plugin is not None or \
            (old.agent is None and old.plugin is None) else old
        other = old if blame is endpoint else endpoint
        issues.append(_issue(world, blame, f"{blame.what} would be the {blame.kind} {full!r} ({blame.type}), "
                                           f"which transport '{transport}' already uses for {other.what} "
                                           f"({other.type}); rename it: each ROS name is used once"))
    return sorted(issues, key=lambda i: (i.line, i.column))


def _issue(world: World, endpoint: Endpoint, text: str) -> WorldIssue:
    """``text`` at the element that brought ``endpoint`` in (the ``<world>`` element for the transport's own)."""
    if endpoint.agent is not None:
        line, column = world.location(endpoint.agent, endpoint.attribute)
        element = endpoint.element or world.agent(endpoint.agent).kind
        return WorldIssue(world.source, line or 1, column or 1, element, None, text)
    if endpoint.plugin is not None:
        plugin = world.plugin(endpoint.plugin)
        if plugin is not None:
            line, column = plugin.location(endpoint.attribute)
            return WorldIssue(world.source, line, column, "plugin", None, text)
    line, column = world.location("", None)
    return WorldIssue(world.source, line or 1, column or 1, "world", None, text)
