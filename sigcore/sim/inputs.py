"""The input log: every command from outside the simulation that changed (or could change) its state, with the step
at which it took effect, so that a run can be re-simulated exactly (``sigcore replay``).

The simulation is deterministic and applies commands only between steps: a transport runs what its clients send
when it is serviced, a viewer what a person does. Whoever applies such a command tells :class:`Inputs` (``sim.inputs``,
the one owner of the log) with :meth:`Inputs.note`; a recorder listens (:attr:`Inputs.listeners`) and keeps them.
A command noted at step ``k`` (``sim.step_count``) took effect after step ``k``'s physics and before step ``k + 1``'s:
a replay applies it there (:meth:`Inputs.apply`), before stepping on.

Kinds (``Input.kind``) and their arguments:

- ``api``: an API table entry called through :func:`sigcore.api.call` (a sig_ros topic or service, a viewer's drag):
  ``agent``, ``entry`` (the suffix, e.g. ``_grasp_obj``), ``request`` (the validated request's fields);
- ``base_velocity``: a drive's ``cmd_vel``: ``robot``, ``linear`` [m/s], ``angular`` [rad/s];
- ``wheel_velocity``: wheels set directly (a ``cmd_vel`` timeout stops them): ``robot``, ``left``, ``right``;
- ``message``: a text message sent to an agent from outside (the viewer): ``sender``, ``to``, ``text``;
- ``reset``: :meth:`Simulation.reset`: ``despawn``;
- ``entity_state``: simulation_interfaces' ``set_entity_state``: ``entity``, ``position``, ``quaternion`` (w, x, y,
  z), ``linear``, ``angular`` (None: not set);
- ``spawn``, ``delete``, ``world``, ``entity_info``: noted (``what`` says what) but not replayed yet: a replay of a
  recording that holds one stops before it, saying so.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from ..errors import SigcoreError

if TYPE_CHECKING:
    from ..api.deferred import Deferred
    from ..api.table import ApiEntry
    from .simulation import Simulation

REPLAYED = ("api", "base_velocity", "wheel_velocity", "message", "reset", "entity_state")
"""The kinds :meth:`Inputs.apply` reproduces."""


class ReplayError(SigcoreError, ValueError):
    """An input cannot be applied again (an unknown kind or entry, a kind not replayed yet)."""


@dataclass(frozen=True)
class Input:
    """One command applied from outside: at step ``step``, of ``kind`` (see the module's docstring), with ``args``
    (JSON-able)."""

    step: int
    kind: str
    args: dict[str, Any] = field(default_factory=dict)

    def to_json(self) -> dict[str, Any]:
        return {"step": self.step, "kind": self.kind, "args": self.args}

    @classmethod
    def from_json(cls, data: dict[str, Any]) -> Input:
        return cls(int(data["step"]), str(data["kind"]), dict(data.get("args") or {}))


class Inputs:
    """The input log of one simulation (``sim.inputs``): tells :attr:`listeners` of every command noted."""

    def __init__(self, sim: Simulation) -> None:
        self._sim = sim
        self.listeners: list[Callable[[Input], None]] = []
        """Called with each :class:`Input` as it is noted (a recorder); nothing is kept otherwise."""

    @property
    def wanted(self) -> bool:
        """Whether anyone listens (a caller may skip building the arguments otherwise)."""
        return bool(self.listeners)

    def note(self, kind: str, **args: Any) -> None:
        """A command of ``kind`` with ``args`` takes effect now (between step ``sim.step_count`` and the next)."""
        if not self.listeners:
            return
        item = Input(self._sim.step_count, kind, args)
        for listener in list(self.listeners):
            listener(item)

    def apply(self, item: Input) -> tuple[ApiEntry, str, Deferred] | None:
        """Apply ``item`` again (a replay), exactly as it was applied: through the same core paths. An API call whose
        answer is deferred returns ``(entry, agent, deferred)``: the caller polls it after each step
        (:func:`sigcore.api.call.finish`), as the transport that took the call did.

        Raises:
            ReplayError: a kind that is not replayed (yet), or an entry the agent does not have.
        """
        sim, a = self._sim, item.args
        if item.kind == "api":
            from ..api.call import call
            from ..api.deferred import Deferred

            kind = sim.agents[a["agent"]].kind if a["agent"] in sim.agents else None
            entry = next((e for e in sim.api_entries() if e.suffix == a["entry"] and kind in e.kinds), None)
            if entry is None:
                raise ReplayError(f"step {item.step}: agent {a['agent']!r} has no API entry {a['entry']!r}")
            result = call(sim, entry, a["agent"], a["request"])
            return (entry, a["agent"], result) if isinstance(result, Deferred) else None
        if item.kind == "base_velocity":
            sim.robot(a["robot"]).set_base_velocity(a["linear"], a["angular"])
        elif item.kind == "wheel_velocity":
            sim.robot(a["robot"]).set_wheel_velocity(a["left"], a["right"])
        elif item.kind == "message":
            sim.send_msg(a["sender"], a["to"], a["text"])
        elif item.kind == "reset":
            sim.reset(despawn=bool(a.get("despawn", True)))
        elif item.kind == "entity_state":
            handle = sim.agent(a["entity"])
            handle.set_position(tuple(a["position"]))
            handle.set_rotation(tuple(a["quaternion"]))
            if a.get("linear") is not None:
                handle.set_velocity(tuple(a["linear"]))
                handle.set_angular_velocity(tuple(a["angular"]))
        else:
            what = a.get("what", "")
            raise ReplayError(f"step {item.step}: a {item.kind}{f' ({what})' if what else ''} was applied here, "
                              f"which sigcore replay does not reproduce yet (it replays: {', '.join(REPLAYED)})")
        return None
