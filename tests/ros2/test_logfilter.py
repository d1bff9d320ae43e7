"""The transport's log filter: once per (endpoint, kind), bounded, suppressed records counted and reported."""

from __future__ import annotations

import logging

import pytest

pytest.importorskip("sigcore_ros2", reason="the sigcore-ros2 plugin is not installed")

from sigcore_ros2.logfilter import OncePerKind  # noqa: E402

from sigcore.api.call import log_key  # noqa: E402


def _record(message: str, endpoint: str | None = None, kind: str = "ApiError",
            level: int = logging.WARNING) -> logging.LogRecord:
    record = logging.LogRecord("sigcore.api", level, __file__, 1, message, None, None)
    if endpoint is not None:
        for key, value in log_key(endpoint, kind).items():
            setattr(record, key, value)
    return record


def test_varied_text_on_one_endpoint_is_logged_once() -> None:
    """Refusals of one endpoint and kind pass once whatever their text; another kind or endpoint passes again."""
    f = OncePerKind()
    passed = [f.filter(_record(f"bot_get_mass refused: no agent '{i}'", "bot_get_mass")) for i in range(1000)]
    assert passed.count(True) == 1
    assert f.filter(_record("invalid", "bot_get_mass", "invalid request"))
    assert f.filter(_record("no agent", "cube_get_mass"))


def test_errors_with_an_endpoint_are_deduplicated_too() -> None:
    """An ERROR about an endpoint passes once per kind; an ERROR without one always passes."""
    f = OncePerKind()
    assert [f.filter(_record("boom", "/x", "KeyError", logging.ERROR)) for _ in range(3)] == [True, False, False]
    assert all(f.filter(_record("start-up failure", level=logging.ERROR)) for _ in range(3))


def test_the_table_of_keys_is_bounded() -> None:
    """Beyond max_keys distinct kinds, new ones are counted, not remembered."""
    f = OncePerKind(max_keys=10)
    passed = [f.filter(_record("r", f"endpoint_{i}")) for i in range(50)]
    assert passed.count(True) == 10 and len(f._seen) == 10


def test_summary_reports_what_was_suppressed(caplog: pytest.LogCaptureFixture) -> None:
    """The summary names the endpoint and count of suppressed records, then starts counting again."""
    f = OncePerKind()
    for _ in range(6):
        f.filter(_record("r", "bot_setMass", "invalid request"))
    logger = logging.getLogger("test.logfilter")
    with caplog.at_level(logging.WARNING, logger="test.logfilter"):
        f.summary(logger)  # the period has not passed yet
        assert not caplog.records
        f.summary(logger, force=True)
        f.summary(logger, force=True)  # nothing new: silent
    assert len(caplog.records) == 1
    assert "5 more refusals/failures suppressed" in caplog.text and "5 of bot_setMass (invalid request)" \
        in caplog.text
