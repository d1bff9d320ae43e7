"""The referee feature: the ``Referee/text/points`` viewer service and, with ``rules="cleanup"``, the clean-up
task's rules detected from the simulation itself."""

from __future__ import annotations

import logging
from typing import Literal

from pydantic import BaseModel

from sigcore.feature import Feature
from sigcore.sim.simulation import Simulation
from sigcore.sim.spawn import EntityChange
from sigcore.world.exceptions import FieldError
from sigcore.world.models import BareAgent, Entity, Object

from .boxes import TrashBox, inner_volume
from .collisions import CollisionRule
from .config import RefereeConfig
from .events import Kind, RefereeEvent, parse_message
from .exceptions import BoxGeometryError, TaskFinishedError
from .items import ItemRule
from .report import report_lines
from .topics import EventMsg, RefereeTopics, ResultMsg

log = logging.getLogger("sigcore.referee")

Result = Literal["running", "succeeded", "failed", "time_limit"]
"""``succeeded``: every trash item at rest in a box that accepts it; ``failed``: every item in a box, some in a
wrong one; ``time_limit``: the time limit came first."""


class Referee(Feature):
    """Keeps the score of a world (``<plugin name="referee" rules="cleanup" .../>``).

    The hand-off to transports: :attr:`score`, :attr:`events` (every :class:`RefereeEvent` in order),
    :attr:`finished`, :attr:`result`, and the publications of :class:`~sigcore_referee.topics.RefereeTopics`
    (``/referee/events`` with every new event as it happens, the last one of a task of kind ``end``; ``/referee/score``;
    ``/referee/result``), which transports, viewers and recorders receive through the core's publication contract.

    Raises:
        FieldError: ``robots`` names no robot, or (``rules="cleanup"``) no entity has the ``trash_tag``.
        ValueError: (``rules="cleanup"``) a trash item no box accepts, or a trash box whose inner volume cannot be
            read.
    """

    name = "referee"

    @classmethod
    def message_types(cls) -> list[type[BaseModel]]:
        """``RefereeEvent`` and ``RefereeResult`` (``/referee/events``, ``/referee/result``)."""
        return [EventMsg, ResultMsg]
    config_model = RefereeConfig

    def __init__(self, sim: Simulation, config: RefereeConfig) -> None:
        self.sim = sim
        self.config = cfg = config
        self.score = 0
        self.events: list[RefereeEvent] = []
        self.finished = False
        self.result: Result = "running"
        self.start_time = sim.time
        self.end_time: float | None = None
        self.items: ItemRule | None = None
        self.collisions: CollisionRule | None = None
        if cfg.rules == "cleanup":
            self._cleanup_rules()
        sim.features.register_service(cfg.service, self.on_message)
        if cfg.rules == "cleanup" or cfg.time_limit > 0:
            self._every = max(1, round(1.0 / (cfg.rate * sim.dt)))
            sim.events.subscribe("step", self._on_step, every=self._every)
        self.topics = RefereeTopics(self)

    def _cleanup_rules(self) -> None:
        cfg, sim = self.config, self.sim
        robots = list(cfg.robots) if cfg.robots is not None else [
            a.name for a in sim.world.entities if a.kind == "robot"]
        unknown = [r for r in robots if r not in sim.entities or sim.entities[r].kind != "robot"]
        if unknown:
            robots_here = [a.name for a in sim.world.entities if a.kind == "robot"]
            raise FieldError("robots", f"'{unknown[0]}' is not a robot of this world; robots: "
                                       f"{', '.join(robots_here) or 'none'}")
        boxes = [self._trash_box(e) for e in sim.world.entities if cfg.box_tag in e.tags]
        items = {a.name: frozenset(a.tags) - {cfg.trash_tag} for a in sim.world.entities if cfg.trash_tag in a.tags}
        if not items:
            raise FieldError("trash_tag", f"rules 'cleanup': no entity is tagged '{cfg.trash_tag}'")
        for item, kinds in items.items():
            if not any(kinds & b.accepts for b in boxes):
                offered = "; ".join(f"{b.name}: {' '.join(sorted(b.accepts))}" for b in boxes) or "none"
                raise ValueError(f"rules 'cleanup': no trash box (tag '{cfg.box_tag}') accepts '{item}' (tags "
                                 f"{' '.join(sorted(kinds)) or 'none'}); boxes: {offered}")
        self.items = ItemRule(sim, cfg, items, boxes, self.award)
        self.collisions = CollisionRule(sim, cfg, robots, self.award)
        sim.events.subscribe("collision", self.collisions.on_collision)

    def _trash_box(self, entity: Entity) -> TrashBox:
        """Entity ``entity`` (tagged ``box_tag``) as a trash box; :class:`BoxGeometryError` if its inner volume
        cannot be read."""
        cfg = self.config
        inner = cfg.box_inner
        if inner is None:
            if not isinstance(entity, Object) or entity.urdf is None:
                raise BoxGeometryError(entity.name, "it is not a URDF object")
            inner = inner_volume(entity.name, self.sim.world.urdf(entity.name), entity.scale)
        return TrashBox(entity.name, frozenset(entity.tags) - {cfg.box_tag}, inner)

    def entities_changed(self, change: EntityChange) -> None:
        """Entities spawned or deleted while running (``rules="cleanup"``): a spawned entity tagged ``box_tag``
        becomes a trash box, one tagged ``trash_tag`` an item to score (kinds: its other tags), one with a
        collision tag furniture, a robot one the rules watch (unless ``robots`` is given); a deleted one is no
        longer expected, and its events stay."""
        if self.items is None or self.collisions is None:
            return
        cfg = self.config
        for name in change.removed:
            self.items.remove(name)
            self.collisions.remove(name)
        added = [self.sim.world.agent(name) for name in change.added]
        entities = [a for a in added if not isinstance(a, BareAgent)]
        for entity in entities:  # boxes first: an item spawned with its box in one call is accepted
            if cfg.box_tag in entity.tags:
                try:
                    self.items.add_box(self._trash_box(entity))
                except BoxGeometryError as e:
                    log.warning("referee: spawned '%s' is not a trash box: %s", entity.name, e)
        for entity in entities:
            if cfg.trash_tag in entity.tags:
                kinds = frozenset(entity.tags) - {cfg.trash_tag}
                if not any(kinds & b.accepts for b in self.items.boxes):
                    log.warning("referee: no trash box accepts spawned item '%s' (tags %s) yet; it can only be put in "
                                "a wrong box", entity.name, " ".join(sorted(kinds)) or "none")
                self.items.add_item(entity.name, kinds)
            self.collisions.add(entity)

    # ------------------------------------------------------------------ scoring
    def award(self, kind: Kind, text: str, points: int) -> None:
        """Record an event and add its points (ignored once the task has ended)."""
        if not self.finished:
            self._record(kind, text, points)

    def _record(self, kind: Kind, text: str, points: int) -> None:
        event = RefereeEvent(round(self.sim.time, 6), kind, text, points)
        self.score += points
        self.events.append(event)
        self.topics.on_event(event)  # the publication contract keeps a sink's failure from the referee

    def on_message(self, sender: str, text: str) -> None:
        """The viewer service: score a ``Referee/<text>/<points>`` message from agent ``sender``.

        Raises:
            MessageFormatError: the text is malformed (the caller gets an error reply).
            TaskFinishedError: the task has ended.
        """
        message = parse_message(text)
        if self.finished:
            assert self.end_time is not None
            raise TaskFinishedError(self.result, self.end_time)
        self.award("message", f"{sender}: {message.text}", message.points)

    def finish(self, result: Result, why: str) -> None:
        """End the task (``finished`` and ``result`` are set when the final ``end`` event is published); stop the
        run if ``stop_on_finish``."""
        if self.finished:
            return
        self.finished, self.result, self.end_time = True, result, self.sim.time
        self._record("end", why, 0)
        if self.config.stop_on_finish:
            self.sim.control.stop("request")

    def reset(self) -> None:
        """Start a new trial from the current state: score, events and rules' memory cleared, clock restarted."""
        self.score, self.finished, self.result = 0, False, "running"
        self.events.clear()
        self.start_time, self.end_time = self.sim.time, None
        if self.items is not None and self.collisions is not None:
            self.items.reset()
            self.collisions.reset()
        self.topics.publish_score()

    def _on_step(self, sim: Simulation) -> None:
        if self.finished or sim.step_count % self._every:
            return
        now = sim.time
        if self.items is not None and self.collisions is not None:
            self.collisions.look(now)
            self.items.look(now)
            if self.items.done:
                wrong = [s.name for s in self.items.items.values() if s.box is not None and not s.correct]
                if wrong:
                    self.finish("failed", f"every trash item is in a box; wrong box: {', '.join(wrong)}")
                else:
                    self.finish("succeeded", f"every trash item is in its correct box ({len(self.items.items)})")
                return
        limit = self.config.time_limit
        if limit > 0 and now - self.start_time >= limit - 1e-9:
            self.finish("time_limit", f"time limit of {limit:g} s reached")

    # ------------------------------------------------------------------ results
    @property
    def succeeded(self) -> bool:
        """Every trash item is at rest in a box that accepts it."""
        return self.result == "succeeded"

    def outcome(self) -> bool | None:
        """The task's verdict for the command line's exit code: None while it runs, then whether it succeeded."""
        return None if not self.finished else self.succeeded

    def summary(self) -> dict[str, object]:
        """Score, result, the number of events by kind, and the task time [s]."""
        end = self.end_time if self.end_time is not None else self.sim.time
        kinds: dict[str, int] = {}
        for e in self.events:
            kinds[e.kind] = kinds.get(e.kind, 0) + 1
        out: dict[str, object] = {"score": self.score, "result": self.result,
                                  "time": round(end - self.start_time, 3), **kinds}
        if self.items is not None:
            out["placed"] = sum(s.box is not None for s in self.items.items.values())
            out["items"] = len(self.items.items)
        return out

    def report(self) -> list[str]:
        """The final score table, one line per event, for the command line to print."""
        return report_lines(self)

    def results(self) -> dict[str, object]:
        """The summary and every event (time [s], kind, text, points, and the total after it)."""
        events, total = [], 0
        for e in self.events:
            total += e.points
            events.append({"time": e.time, "kind": e.kind, "text": e.text, "points": e.points, "score": total})
        return {**self.summary(), "events": events}
