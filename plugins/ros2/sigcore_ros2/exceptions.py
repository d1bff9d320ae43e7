"""The errors of sigcore_ros2."""

from __future__ import annotations

from typing import TYPE_CHECKING

from sigcore.errors import SigcoreError

if TYPE_CHECKING:
    from simulation_interfaces.msg import Result


class Refusal(SigcoreError):
    """A request that is answered with ``code`` and ``message`` (a simulation_interfaces Result)."""

    def __init__(self, code: int, message: str) -> None:
        super().__init__(message)
        self.code = code
        self.message = message

    def result(self) -> Result:
        """The Result to answer with."""
        from simulation_interfaces.msg import Result

        return Result(result=self.code, error_message=self.message)


class RosToolError(SigcoreError, RuntimeError):
    """A ``sigcore ros`` command cannot go on: ``code`` 2 for bad input (an unknown topic, service, type or field,
    malformed YAML), 1 for what happened (a timeout, no message)."""

    def __init__(self, message: str, code: int = 2) -> None:
        super().__init__(message)
        self.code = code
