"""The input log: every command from outside the simulation that changed (or could change) its state, with the step
at which it took effect, so that a run can be re-simulated exactly (``sigcore replay``).

The simulation is deterministic and applies commands only between steps: a transport runs what its clients send
when it is serviced, a viewer what a person does. Every such command goes through a verb of :class:`Inputs`
(``sim.inputs``, the one owner of the log: :meth:`~Inputs.base_velocity`, :meth:`~Inputs.person_velocity`,
:meth:`~Inputs.person_path`, :meth:`~Inputs.person_joints`, :meth:`~Inputs.wheel_velocity`, :meth:`~Inputs.message`,
:meth:`~Inputs.entity_state`, :meth:`~Inputs.entity_info`, :meth:`~Inputs.spawn`, :meth:`~Inputs.delete`,
:meth:`~Inputs.load_world`, :meth:`~Inputs.unload_world`), or through the API table (:func:`sigcore.api.call`) or
:meth:`Simulation.reset`, which note themselves: the core applies the command and notes it, whichever client applied
it, so a new transport cannot forget to. A recorder subscribes to the ``input`` channel of ``sim.events`` and keeps
them.
A command noted at step ``k`` (``sim.step_count``) took effect after step ``k``'s physics and before step ``k + 1``'s:
a replay applies it there (:meth:`Inputs.apply`), before stepping on.

Kinds (``Input.kind``) and their arguments:

- ``api``: an API table entry called through :func:`sigcore.api.call` (a sig_ros topic or service, a viewer's drag):
  ``agent``, ``entry`` (the suffix, e.g. ``_grasp_obj``), ``request`` (the validated request's fields);
- ``base_velocity``: a drive's ``cmd_vel``: ``robot``, ``linear`` [m/s], ``angular`` [rad/s];
- ``person_velocity``: a person's walk (``/<person>/cmd_vel``): ``person``, ``linear`` [m/s], ``angular`` [rad/s];
- ``person_path``: a path for a person to walk (``/<person>/path``): ``person``, ``path`` (the
  :class:`~sigcore.world.models.WalkPath`'s fields: ``speed``, ``loop``, ``waypoints``);
- ``person_joints``: a person's skeleton (``/<person>/skeleton``): ``person``, ``positions`` (REP-155 joint names
  and ``root_*`` -> values);
- ``wheel_velocity``: wheels set directly (a ``cmd_vel`` timeout stops them): ``robot``, ``left``, ``right``;
- ``message``: a text message sent to an agent from outside (the viewer): ``sender``, ``to``, ``text``;
- ``reset``: :meth:`Simulation.reset`: ``despawn``;
- ``entity_state``: simulation_interfaces' ``set_entity_state``: ``entity``, ``position``, ``quaternion`` (w, x, y,
  z), ``linear``, ``angular`` (None: not set);
- ``spawn``: simulation_interfaces' ``spawn_entity`` / ``spawn_entities``, one input per call (a batch stays one
  batch, so renaming and order are the same): ``requests`` (every :class:`~sigcore.world.resources.SpawnRequest` passed
  to :meth:`Simulation.spawn`, in order, as a dict of its fields, tuples as lists), ``names`` (per request the name
  it got, or None when it was refused: a replay checks that it gets the same), ``what``; noted by
  :meth:`Inputs.note_spawn` after the call, refusals included;
- ``delete``: ``delete_entity`` that succeeded: ``entities`` (names), ``what``;
- ``entity_info``: ``set_entity_info`` that succeeded: ``entity``, ``category`` (the core's name, e.g.
  ``static_object``), ``description``, ``tags``, ``what``;
- ``world``: ``load_world`` (``uri``, ``resource_string`` as given) and ``unload_world``, with ``what``: noted but not
  replayed: a replay of a recording that holds one stops before it, saying so (a world load restarts the step count
  and the recording's clock).

A ``spawn``, ``delete`` or ``entity_info`` recorded before they were replayed holds only ``what``: it is refused the
same way (:func:`refusal`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, fields
from typing import TYPE_CHECKING, Any

from ..world.models import WalkPath
from .exceptions import ReplayError

if TYPE_CHECKING:
    from ..api.deferred import Deferred
    from ..api.table import ApiEntry
    from ..world.exceptions import SpawnRefusal
    from ..world.models import World
    from ..world.resources import SpawnRequest
    from .info import EntityInfo
    from .simulation import Simulation

REPLAYED = ("api", "base_velocity", "person_velocity", "person_path", "person_joints", "wheel_velocity", "message",
            "reset", "entity_state", "spawn", "delete", "entity_info")
"""The kinds :meth:`Inputs.apply` reproduces."""

_NEEDED = {"spawn": "requests", "delete": "entities", "entity_info": "category"}
"""Kinds noted with only ``what`` by older sigcores: the argument the full form has."""


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


def refusal(item: Input) -> str | None:
    """Why ``item`` cannot be applied again (naming its step and offering ``--until``), or None when it can: a kind
    not replayed (``world``, an unknown one), or one recorded with only ``what`` (before sigcore replayed it)."""
    what = item.args.get("what") or item.kind
    if item.kind not in REPLAYED:
        return (f"step {item.step}: the run applied '{what}', which replay does not reproduce yet (it replays: "
                f"{', '.join(REPLAYED)}); --until {item.step} replays up to it")
    needed = _NEEDED.get(item.kind)
    if needed is not None and needed not in item.args:
        return (f"step {item.step}: the run applied '{what}', recorded without its arguments (by a sigcore that "
                f"did not replay '{item.kind}' yet): it cannot be applied again; --until {item.step} replays up to it")
    return None


def spawn_request_args(request: SpawnRequest) -> dict[str, Any]:
    """Every field of ``request`` (tuples as lists): a ``spawn`` input's ``requests`` item."""
    return {f.name: list(value) if isinstance(value := getattr(request, f.name), tuple) else value
            for f in fields(request)}


def spawn_request_of(args: dict[str, Any]) -> SpawnRequest:
    """The request :func:`spawn_request_args` gave ``args`` for."""
    from ..world.resources import SpawnRequest

    known = {f.name for f in fields(SpawnRequest)}
    unknown = sorted(set(args) - known)
    if unknown:
        raise ReplayError(f"a spawn request with fields this sigcore does not know: {', '.join(unknown)}")
    values: dict[str, Any] = {k: tuple(v) if isinstance(v, list) else v for k, v in args.items()}
    return SpawnRequest(**values)


class Inputs:
    """The input log of one simulation (``sim.inputs``): emits every command noted on the ``input`` channel of
    ``sim.events`` (a recorder subscribes); nothing is kept otherwise."""

    def __init__(self, sim: Simulation) -> None:
        self._sim = sim

    @property
    def wanted(self) -> bool:
        """Whether anyone listens (a caller may skip building the arguments otherwise)."""
        return self._sim.events.wanted("input")

    def note(self, kind: str, **args: Any) -> None:
        """A command of ``kind`` with ``args`` takes effect now (between step ``sim.step_count`` and the next)."""
        events = self._sim.events
        if events.wanted("input"):
            events.emit("input", Input(self._sim.step_count, kind, args))

    def note_spawn(self, requests: Sequence[SpawnRequest], outcomes: Sequence[str | SpawnRefusal],
                   what: str = "") -> None:
        """``requests`` were just passed to :meth:`Simulation.spawn` (one call) and gave ``outcomes`` (a name, or
        the refusal): one ``spawn`` input."""
        if self.wanted:
            self.note("spawn", requests=[spawn_request_args(r) for r in requests],
                      names=[o if isinstance(o, str) else None for o in outcomes], what=what)

    # ------------------------------------------------------------------ commands from outside: applied, then noted
    def base_velocity(self, robot: str, linear: float, angular: float) -> None:
        """Drive ``robot``'s base (a ``cmd_vel``): ``linear`` [m/s], ``angular`` [rad/s].

        Raises:
            ApiError: no such robot, it has no drive, or a value is not finite (nothing noted then).
        """
        self._sim.robot(robot).set_base_velocity(linear, angular)
        self.note("base_velocity", robot=robot, linear=linear, angular=angular)

    def person_velocity(self, person: str, linear: float, angular: float) -> None:
        """Walk ``person`` (a ``/<person>/cmd_vel``): ``linear`` [m/s], ``angular`` [rad/s] (``sim.entities.people``).

        Raises:
            ApiError: no such person, or a value out of range or not finite (nothing noted then).
        """
        self._sim.entities.people.walk(person, linear, angular)
        self.note("person_velocity", person=person, linear=linear, angular=angular)

    def person_path(self, person: str, path: WalkPath) -> None:
        """Walk ``person`` along ``path`` (a ``/<person>/path``; ``sim.entities.people``).

        Raises:
            ApiError: no such person, or the path cannot be walked (nothing noted then).
        """
        self._sim.entities.people.follow(person, path)
        self.note("person_path", person=person, path=path.model_dump(mode="json", exclude_unset=True))

    def person_joints(self, person: str, positions: Mapping[str, float]) -> None:
        """Put ``person``'s joints and feet frame at ``positions`` (a ``/<person>/skeleton``;
        ``sim.entities.people.set_joints``).

        Raises:
            ApiError: no such person, an unknown name, a value not finite or out of range (nothing noted then).
        """
        self._sim.entities.people.set_joints(person, positions)
        self.note("person_joints", person=person, positions={str(k): float(v) for k, v in positions.items()})

    def wheel_velocity(self, robot: str, left: float, right: float) -> None:
        """Set ``robot``'s wheel velocities directly [rad/s] (a ``cmd_vel`` timeout stops them so)."""
        self._sim.robot(robot).set_wheel_velocity(left, right)
        self.note("wheel_velocity", robot=robot, left=left, right=right)

    def message(self, sender: str, to: str, text: str) -> None:
        """Send a text message to agent ``to`` from ``sender`` (a viewer, a person, a client): delivered before the
        next step."""
        self._sim.send_msg(sender, to, text)
        self.note("message", sender=sender, to=to, text=text)

    def entity_state(self, entity: str, position: Sequence[float], quaternion: Sequence[float],
                     linear: Sequence[float] | None = None, angular: Sequence[float] | None = None) -> None:
        """Put ``entity`` at ``position`` [m] with orientation ``quaternion`` (w, x, y, z), and give it ``linear``
        [m/s] and ``angular`` [rad/s] velocities (None: not set)."""
        handle = self._sim.agent(entity)
        handle.set_position(tuple(position))
        handle.set_rotation(tuple(quaternion))
        if linear is not None:
            handle.set_velocity(tuple(linear))
            handle.set_angular_velocity(tuple(angular if angular is not None else (0.0, 0.0, 0.0)))
        self.note("entity_state", entity=entity, position=list(position), quaternion=list(quaternion),
                  linear=list(linear) if linear is not None else None,
                  angular=list(angular) if linear is not None and angular is not None else None)

    def entity_info(self, entity: str, category: str, description: str, tags: Sequence[str],
                    what: str = "") -> EntityInfo:
        """Replace ``entity``'s category, description and tags (``sim.entities.info``); the information now."""
        info = self._sim.entities.info.set(entity, category, description, list(tags))
        self.note("entity_info", entity=entity, category=info.category, description=info.description,
                  tags=list(info.tags), what=what or f"set_entity_info {entity}")
        return info

    def spawn(self, requests: Sequence[SpawnRequest], what: str = "") -> list[str | SpawnRefusal]:
        """:meth:`Simulation.spawn` of ``requests`` (one call), noted with what each gave (refusals included)."""
        outcomes = self._sim.entities.spawn(requests)
        self.note_spawn(requests, outcomes, what or f"spawn ({len(requests)})")
        return outcomes

    def delete(self, names: Sequence[str], what: str = "") -> None:
        """:meth:`Simulation.delete` of ``names``; noted when done (a refusal raises and notes nothing)."""
        self._sim.entities.delete(names)
        self.note("delete", entities=list(names), what=what or f"delete {', '.join(names)}")

    def load_world(self, world: World, uri: str = "", resource_string: str = "") -> None:
        """``sim.worlds.load`` of ``world`` (named by ``uri`` or given as ``resource_string``); noted
        first, as it ends what the recording can replay."""
        self.note("world", what=f"load_world {world.name}", uri=uri, resource_string=resource_string)
        self._sim.worlds.load(world)

    def unload_world(self) -> None:
        """``sim.worlds.unload``; noted first."""
        self.note("world", what="unload_world")
        self._sim.worlds.unload()

    # ------------------------------------------------------------------ replay
    def apply(self, item: Input) -> tuple[ApiEntry, str, Deferred] | None:
        """Apply ``item`` again (a replay), exactly as it was applied: through the same core paths. An API call whose
        answer is deferred returns ``(entry, agent, deferred)``: the caller polls it after each step
        (:func:`sigcore.api.call.finish`), as the transport that took the call did.

        Raises:
            ReplayError: a kind that is not replayed (yet) or was recorded without its arguments, an entry the agent
                does not have, a spawn that does not get what it got when recorded (a file it names is gone), a
                delete or an entity information change refused now.
        """
        sim, a = self._sim, item.args
        if item.kind == "api":
            from ..api.call import call
            from ..api.deferred import Deferred

            kind = sim.entities[a["agent"]].kind if a["agent"] in sim.entities else None
            entry = next((e for e in sim.api_entries() if e.suffix == a["entry"] and kind in e.kinds), None)
            if entry is None:
                raise ReplayError(f"step {item.step}: agent {a['agent']!r} has no API entry {a['entry']!r}")
            result = call(sim, entry, a["agent"], a["request"])
            return (entry, a["agent"], result) if isinstance(result, Deferred) else None
        if item.kind == "base_velocity":
            self.base_velocity(a["robot"], a["linear"], a["angular"])
        elif item.kind == "person_velocity":
            self.person_velocity(a["person"], a["linear"], a["angular"])
        elif item.kind == "person_path":
            self.person_path(a["person"], WalkPath.model_validate(a["path"]))
        elif item.kind == "person_joints":
            self.person_joints(a["person"], a["positions"])
        elif item.kind == "wheel_velocity":
            self.wheel_velocity(a["robot"], a["left"], a["right"])
        elif item.kind == "message":
            self.message(a["sender"], a["to"], a["text"])
        elif item.kind == "reset":
            sim.reset(despawn=bool(a.get("despawn", True)))
        elif item.kind == "entity_state":
            self.entity_state(a["entity"], a["position"], a["quaternion"], a.get("linear"), a.get("angular"))
        elif (why := refusal(item)) is not None:
            raise ReplayError(why)
        elif item.kind == "spawn":
            self._spawn(item)
        elif item.kind == "delete":
            from ..world.exceptions import SpawnRefusal

            try:
                self.delete(list(a["entities"]), a.get("what", ""))
            except SpawnRefusal as e:
                raise ReplayError(f"step {item.step}: deleting {', '.join(map(repr, a['entities']))} is refused "
                                  f"now ({e.code}: {e}), it was done when recorded") from None
        elif item.kind == "entity_info":
            from ..agent.exceptions import ApiError

            try:
                self.entity_info(a["entity"], a["category"], a["description"], list(a["tags"]), a.get("what", ""))
            except ApiError as e:
                raise ReplayError(f"step {item.step}: set_entity_info of {a['entity']!r} is refused now ({e}), it "
                                  "was done when recorded") from None
        return None

    def _spawn(self, item: Input) -> None:
        """A ``spawn`` again: the same requests in one call; each must get what it got when recorded."""
        try:
            requests = [spawn_request_of(r) for r in item.args["requests"]]
        except ReplayError as e:
            raise ReplayError(f"step {item.step}: {e}") from None
        outcomes = self.spawn(requests, item.args.get("what", ""))
        names = item.args.get("names")
        if names is None:
            return
        for request, outcome, recorded in zip(requests, outcomes, names, strict=True):
            now = outcome if isinstance(outcome, str) else None
            if now == recorded:
                continue
            source = f"uri {request.uri!r}" if request.uri.strip() else "its resource text"
            what = f"step {item.step}: the spawn of {source}" + (f" (name {request.name!r})" if request.name else "")
            if not isinstance(outcome, str):
                raise ReplayError(f"{what} is refused now ({outcome.code}: {outcome}); when recorded it spawned "
                                  f"'{recorded}' (the files a spawn names must still be there to replay it)")
            if recorded is None:
                raise ReplayError(f"{what} spawned '{now}' now, but was refused when recorded")
            raise ReplayError(f"{what} spawned '{now}' now, '{recorded}' when recorded")
