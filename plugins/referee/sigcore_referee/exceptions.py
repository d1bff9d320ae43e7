"""Errors of the referee: each carries its data and says what would be valid."""

from __future__ import annotations

from sigcore.agent.exceptions import ApiError
from sigcore.errors import SigcoreError

MESSAGE_FORMAT = "Referee/<text>/<points>"
"""The sig_ros referee message format: ``points`` is an integer (negative for a penalty)."""


class MessageFormatError(ApiError):
    """A ``_send_msg_to_srv`` text the referee cannot read; the API answers it as an error reply.

    Attributes:
        text: The text received.
        reason: What is wrong with it.
    """

    def __init__(self, text: str, reason: str) -> None:
        self.text, self.reason = text, reason
        shown = text if len(text) <= 80 else text[:77] + "..."
        super().__init__(f"malformed referee message {shown!r}: {reason}; expected '{MESSAGE_FORMAT}' with "
                         "integer points, e.g. 'Referee/collision with the wall/-100'")


class TaskFinishedError(ApiError):
    """A referee message arrived after the task ended: the score is final.

    Attributes:
        result: The task's result (``succeeded``, ``failed``, ``time_limit``).
        time: When it ended [s].
    """

    def __init__(self, result: str, time: float) -> None:
        self.result, self.time = result, time
        super().__init__(f"the task ended at t = {time:.2f} s ({result}); the score is final")


class BoxGeometryError(SigcoreError, ValueError):
    """The inner volume of a trash box cannot be read from its model; set ``box_inner`` on the plugin.

    Attributes:
        box: The trash box entity.
        reason: Why its geometry was not understood.
    """

    def __init__(self, box: str, reason: str) -> None:
        self.box, self.reason = box, reason
        super().__init__(f"cannot find the inner volume of trash box '{box}': {reason}; give it as "
                         "box_inner=\"x0 y0 z0 x1 y1 z1\" [m] (two corners in the box's frame)")
