"""The referee's publications: the score, each scored event and the result, through the core's contract.

- ``/referee/score`` (``std_msgs/msg/Int32``, latched): the current total, after every event and at the start;
- ``/referee/events`` (``sigcore_msgs/msg/RefereeEvent``): each event as it happens, with the total after it;
- ``/referee/result`` (``sigcore_msgs/msg/RefereeResult``, latched): once the task has ended, with the score table.

Transports create these topics from the declarations; nothing here knows a transport.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from sigcore.api.types import message_model
from sigcore.publish import Publication

from .report import report_lines

if TYPE_CHECKING:
    from .events import RefereeEvent
    from .referee import Referee

EventMsg = message_model(
    "RefereeEvent", "One scored event of the referee (`kind`: grasp, correct_box, wrong_box, outside, collision, "
    "message, end).\ntime: simulation time [s]; points: added to the score; score: the total after it.",
    time=float, kind=str, text=str, points=int, score=int)
ResultMsg = message_model(
    "RefereeResult", "The end of the task: `result` is succeeded, failed or time_limit.\nscore: the final "
    "total; time: the task's duration [s]; report: the score table, one line each (as `sigcore run` prints it).",
    result=str, score=int, time=float, report=list[str])

SCORE = "/referee/score"
EVENTS = "/referee/events"
RESULT = "/referee/result"


class RefereeTopics:
    """Declares the referee's publications and pushes its score, events and result.

    Args:
        referee: The referee (it hands each new event to :meth:`on_event`).
    """

    def __init__(self, referee: Referee) -> None:
        self.referee = referee
        declare = referee.sim.publications.declare
        self._score = declare(Publication(SCORE, "std_msgs/msg/Int32", "latched", "the referee's current total",
                                          "referee", display="value", display_format="score: {data}"))
        self._events = declare(Publication(EVENTS, "RefereeEvent", "events", "each scored event as it happens",
                                           "referee", model=EventMsg, display="log",
                                           display_format="{time:7.2f} s  {points:+5d}  {text}"))
        self._result = declare(Publication(RESULT, "RefereeResult", "latched",
                                           "the result and the score table, once the task has ended", "referee",
                                           model=ResultMsg, display="result",
                                           display_format="{result}: score {score} after {time:.1f} s"))
        self.publish_score()

    def publish_score(self) -> None:
        """Push the current total (at the start and after a reset)."""
        self._score.publish({"data": self.referee.score})

    def on_event(self, event: RefereeEvent) -> None:
        """Push the event and the new total; the result when the task has ended."""
        referee = self.referee
        self._events.publish({"time": event.time, "kind": event.kind, "text": event.text, "points": event.points,
                              "score": referee.score})
        self.publish_score()
        if event.kind == "end":
            end = referee.end_time if referee.end_time is not None else referee.sim.time
            self._result.publish({"result": referee.result, "score": referee.score,
                                  "time": round(end - referee.start_time, 6), "report": report_lines(referee)})
