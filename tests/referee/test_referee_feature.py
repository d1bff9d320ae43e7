"""The referee feature: time limit, end of the task, its publications (the transports' hand-off), summary and
table."""

from __future__ import annotations

import logging
from pathlib import Path
from typing import Any

import pytest
from referee_worlds import BOXES, ITEMS, MODERATOR, make_sim, run_for
from sigcore_referee import Referee, RefereeEvent
from sigcore_referee.exceptions import TaskFinishedError

from sigcore import plugins
from sigcore.publish import Publication, PublicationSink
from sigcore.sim import Simulation, run


class Sink(PublicationSink):
    """Keeps what the referee publishes, by topic; ``broken`` raises on every value."""

    def __init__(self, broken: bool = False, seen: list[tuple[str, dict[str, Any]]] | None = None) -> None:
        self.broken = broken
        self.seen: list[tuple[str, dict[str, Any]]] = [] if seen is None else seen

    def declare(self, publication: Publication) -> None:
        pass

    def publish(self, publication: Publication, stamp_ns: int, value: dict[str, Any]) -> None:
        if self.broken:
            raise RuntimeError("publisher gone")
        if publication.topic.startswith("/referee/"):
            self.seen.append((publication.topic, value))


def _referee(sim: Simulation) -> Referee:
    ref = sim.features["referee"]
    assert isinstance(ref, Referee)
    return ref


def test_registered_as_feature_referee() -> None:
    """The installed plugin provides feature 'referee' and controller 'cleanup.robot'."""
    assert plugins.get_feature("referee") is Referee
    assert "cleanup.robot" in plugins.controllers()


def test_time_limit_ends_the_task(tmp_path: Path) -> None:
    """time_limit="1": the task ends at 1 s with result 'time_limit'; later events and messages are refused."""
    sim = make_sim(tmp_path, BOXES + ITEMS + MODERATOR, 'rules="cleanup" time_limit="1"')
    ref = _referee(sim)
    run_for(sim, 0.9)
    assert not ref.finished and ref.result == "running"
    run_for(sim, 0.2)
    assert ref.finished and ref.result == "time_limit" and not ref.succeeded
    assert ref.end_time == pytest.approx(1.0)
    assert ref.events == [RefereeEvent(1.0, "end", "time limit of 1 s reached", 0)]
    sim.entities["can_0"].set_position([0.0, 0.0, 0.6])
    run_for(sim, 2.0)
    assert ref.score == 0 and len(ref.events) == 1
    with pytest.raises(TaskFinishedError, match="ended at t = 1.00 s"):
        ref.on_message("moderator_0", "Referee/late/10")
    with pytest.raises(TaskFinishedError):
        ref.on_message("moderator_0", "Referee/late/10")


def test_stop_on_finish_stops_the_run(tmp_path: Path) -> None:
    """stop_on_finish="true": sigcore.sim.run returns when the task ends, before the requested duration."""
    sim = make_sim(tmp_path, BOXES + ITEMS, 'rules="cleanup" time_limit="0.5" stop_on_finish="true"')
    report = run(sim, duration=5.0)
    assert report.sim_time == pytest.approx(0.5, abs=0.01)
    assert report.summary["referee"] == {"score": 0, "result": "time_limit", "time": 0.5, "end": 1, "placed": 0,
                                         "items": 2}


def test_no_time_limit(tmp_path: Path) -> None:
    """time_limit="0": the task does not end by itself."""
    sim = make_sim(tmp_path, BOXES + ITEMS, 'rules="cleanup" time_limit="0"')
    run_for(sim, 2.0)
    assert not _referee(sim).finished


def test_every_event_is_published_and_a_raising_sink_breaks_nothing(tmp_path: Path,
                                                                    caplog: pytest.LogCaptureFixture) -> None:
    """Every event is published on /referee/events as it is recorded, with the running score; a sink that raises is
    logged and the others (and the referee) go on."""
    sim = make_sim(tmp_path, BOXES + ITEMS, 'rules="cleanup"')
    ref = _referee(sim)
    sink = Sink()
    sim.publications.connect(Sink(broken=True))
    sim.publications.connect(sink)
    sim.entities["can_0"].set_position([0.0, 0.0, 0.6])
    sim.entities["petbottle_1"].set_position([1.0, 0.0, 0.6])
    with caplog.at_level(logging.ERROR, "sigcore"):
        run_for(sim, 3.0)
    events = [value for topic, value in sink.seen if topic == "/referee/events"]
    assert [(e["kind"], e["points"]) for e in events] == [(e.kind, e.points) for e in ref.events]
    assert [e["kind"] for e in events] == ["correct_box", "correct_box", "end"]
    assert events[-1]["score"] == ref.score
    assert "publisher gone" in caplog.text


def test_report_is_the_score_table(tmp_path: Path) -> None:
    """report() has a verdict line, one line per event with the running total, and a total line."""
    sim = make_sim(tmp_path, BOXES + ITEMS, 'rules="cleanup"')
    ref = _referee(sim)
    sim.entities["can_0"].set_position([1.0, 0.0, 0.6])
    sim.entities["petbottle_1"].set_position([1.0, 0.1, 0.7])
    run_for(sim, 3.0)
    lines = ref.report()
    assert lines[0].startswith("referee (cleanup rules): failed at t = ") and lines[0].endswith("score 400")
    rows = [line.split() for line in lines[2:-1]]
    assert [(r[1], r[2], r[3]) for r in rows] == [("wrong_box", "-600", "-600"), ("correct_box", "+1000", "400"),
                                                  ("end", "+0", "400")]
    assert lines[-1] == "  total 400: wrong_box 1x -600, correct_box 1x +1000"


def test_reset_starts_a_new_trial(tmp_path: Path) -> None:
    """reset() clears score, events and the end, and restarts the clock from now."""
    sim = make_sim(tmp_path, BOXES + ITEMS, 'rules="cleanup" time_limit="1"')
    ref = _referee(sim)
    run_for(sim, 1.2)
    assert ref.finished
    sim.reset()
    ref.reset()
    assert (ref.score, ref.events, ref.finished, ref.result) == (0, [], False, "running")
    run_for(sim, 0.5)
    assert not ref.finished
    run_for(sim, 0.6)
    assert ref.finished and ref.end_time == pytest.approx(2.2)


def test_the_result_is_published_with_the_end_event(tmp_path: Path) -> None:
    """The 'end' event is published when finished and result are already set: the result follows it at once."""
    sim = make_sim(tmp_path, BOXES + ITEMS, 'rules="cleanup" time_limit="0.3"')
    sink = Sink()
    sim.publications.connect(sink)
    run_for(sim, 0.5)
    topics = [(topic, value.get("kind", value.get("result"))) for topic, value in sink.seen
              if topic != "/referee/score"]
    assert topics == [("/referee/events", "end"), ("/referee/result", "time_limit")]
