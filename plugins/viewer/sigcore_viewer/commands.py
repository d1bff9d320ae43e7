"""The person's commands from the browser (play, pause, step, reset, the pace, a message to an agent, a dragged
entity, an overlay's switch): each a function run on the simulation thread between steps that returns a note to show,
and the command a request of the panel stands for. They reach the simulation through the same run control and API a
ROS 2 client uses.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np

from sigcore.api.call import call
from sigcore.sim.exceptions import RunStateError
from sigcore.text import clip, quote
from sigcore.viewer import VIEWER_SENDER
from sigcore.world.models import Object

if TYPE_CHECKING:
    from sigcore.sim.simulation import Simulation

Command = Callable[["Simulation"], "str | None"]
"""What a person asked, run on the simulation thread between steps; returns a note to show, or None."""

PACES: dict[str, float | None] = {"real time": 1.0, "0.25x": 0.25, "0.5x": 0.5, "2x": 2.0, "5x": 5.0,
                                  "10x": 10.0, "as fast as possible": None}
"""The paces a person may pick (simulated seconds per wall second; None: as fast as possible)."""


def pace_name(factor: float | None) -> str:
    """The name of ``factor`` among :data:`PACES`, or ``"<f>x"``."""
    for name, value in PACES.items():
        if value == factor:
            return name
    return f"{factor:g}x"


def command_of(message: tuple[Any, ...], select: Callable[[str], Command],
               move: Callable[[str, Any, Any], Command], overlay: Callable[[str, bool], Command]) -> Command:
    """The command a person's request (from the panel, in the viewer's process) stands for; ``select``, ``move``
    and ``overlay`` make the commands that act on the viewer as well (its selection, the drag handle, the switches).
    A request that is not known, or has the wrong arguments, becomes a command that answers a note."""
    kind, args = message[0], message[1:]
    simple: dict[str, Command] = {"play": play, "pause": pause, "reset": reset}
    if kind in simple and not args:
        return simple[kind]
    made: dict[str, Callable[..., Command]] = {
        "step": step, "pace": set_pace, "send": send_message, "select": select, "move": move, "overlay": overlay}
    if kind in made:
        try:
            return made[kind](*args)
        except TypeError:
            pass
    return lambda sim: f"the viewer sent a request sigcore does not know: {clip(repr(message), 80)}"


def play(sim: Simulation) -> str | None:
    try:
        sim.control.play()
    except RunStateError as e:
        return str(e)
    return None


def pause(sim: Simulation) -> str | None:
    sim.control.pause()
    return None


def step(n: Any) -> Command:
    def run(sim: Simulation) -> str | None:
        try:
            value = float(n)
        except (TypeError, ValueError):
            return f"steps must be a whole number from 1 to 100000, got {quote(str(n))}"
        if not value.is_integer() or not (1 <= value <= 100000):
            return f"steps must be a whole number from 1 to 100000, got {n}"
        try:
            sim.control.step(int(value))
        except RunStateError as e:
            return str(e)
        return None
    return run


def reset(sim: Simulation) -> str | None:
    held = sim.entities.grasps.items() if sim.worlds.loaded else []
    try:
        sim.control.request_reset()
    except RunStateError as e:
        return str(e)
    if held:
        released = "; ".join(f"{robot} let go of {obj}" for robot, _, obj in held)
        return f"reset to the start: {released}"
    return "reset to the start"


def set_pace(name: str) -> Command:
    def run(sim: Simulation) -> str | None:
        if name not in PACES:
            return f"unknown pace {quote(name)}; valid: {', '.join(PACES)}"
        sim.control.set_pace(PACES[name])
        return None
    return run


def send_message(agent: str, text: str) -> Command:
    def run(sim: Simulation) -> str | None:
        if not agent:
            return "pick an agent to send the message to"
        if not text.strip():
            return "type a message first"
        if agent not in sim.entities:
            return (f"agent {quote(agent)} no longer exists: the message was not sent; agents: "
                    f"{', '.join(sim.entities) or 'none'}")
        sim.inputs.message(VIEWER_SENDER, agent, text)
        return f"sent to {agent}: {clip(text, 80)}"
    return run


def move_entity(name: str, position: np.ndarray, wxyz: np.ndarray) -> Command:
    """Teleport ``name`` through the API entries ``_setPosition`` and ``_setRotation`` (what a ROS client calls)."""
    def run(sim: Simulation) -> str | None:
        if name not in sim.entities:
            return f"{quote(name)} no longer exists: nothing was moved"
        model = next((e for e in sim.world.entities if e.name == name), None)
        if isinstance(model, Object) and model.static:
            return (f"{name} is static (fixed in place): it cannot be dragged; movable objects, robots and people "
                    "can")
        entries = {e.suffix: e for e in sim.api_entries()}
        p, q = [float(v) for v in position], [float(v) for v in wxyz]
        if not all(math.isfinite(x) for x in p + q) or not any(q):
            return (f"{name} was not moved: the position {p} [m] and the quaternion (w x y z) {q} must be finite "
                    "numbers, the quaternion non-zero")
        requests = [("_setPosition", {"name": name, "x": p[0], "y": p[1], "z": p[2]}),
                    ("_setRotation", {"name": name, "qw": q[0], "qx": q[1], "qy": q[2], "qz": q[3]})]
        if isinstance(model, Object) and sim.entities.mode(name, "dynamics"):  # put down at rest, not thrown
            requests += [("_setVelocity", {"name": name}), ("_setAngularVelocity", {"name": name})]
        for suffix, request in requests:
            answer = call(sim, entries[suffix], name, request)
            if isinstance(answer, dict) and not answer.get("success", False):
                return f"{name} was not moved: {answer.get('message', '')}"
        return None
    return run


def switch_overlay(overlays: dict[str, bool], key: str, on: bool) -> Command:
    """Turn the overlay ``key`` of ``overlays`` (the viewer's switches) on or off."""
    def run(sim: Simulation) -> str | None:
        if key not in overlays:
            return f"unknown overlay {quote(str(key))}; valid: {', '.join(overlays)}"
        overlays[key] = bool(on)
        return None
    return run
