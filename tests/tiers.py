"""How the suite is split and spread: the tiers (markers), the parallel workers, and the order work is handed out.

* Markers (registered in ``pyproject.toml``): ``ros2`` (starts ROS 2 nodes; skipped where rclpy cannot be imported),
  ``browser`` (a real headless chromium), ``slow`` (2 s or more on its own on an idle machine). The fast tier is
  ``-m "not slow and not ros2 and not browser"``.
* Workers: ``-n auto`` (``pyproject.toml``) starts :func:`auto_workers` pytest-xdist workers: two per core, at most
  :data:`rosdomains.WORKERS` (each has a ROS 2 domain range of its own): the tests mostly wait on processes, pacing
  and discovery, so more workers than cores keep both busy (the whole suite used 1.6 of 2 cores with four workers;
  six were hardly faster, 599 s against 618 s, and two timing-bound tests failed under the load).
* Groups (``--dist loadgroup``): the tests of a module that use a module-scoped fixture (a simulation process, a
  recorded run) stay in one worker, so that fixture is built once; other tests are handed out one by one.
* Order: the longest work first (the longest-processing-time rule), so that no long test starts last and runs alone:
  a group's or test's cost is its seconds in ``tests/durations.json`` (refreshed with ``--store-durations``), else a
  guess from its markers (:data:`GUESS`).
"""

from __future__ import annotations

import importlib.util
import json
import os
from pathlib import Path

import pytest
import rosdomains
from _pytest.nodeid import coerce_node_id

DURATIONS = Path(__file__).with_name("durations.json")
"""``{"modules": [test files measured], "seconds": {node id: seconds}}``: the measured seconds of the tests that took
at least :data:`KEEP` s; a test of a measured file that is not listed took less (:data:`SHORT`)."""
KEEP = 1.0
SHORT = 0.2
GUESS = {"slow": 20.0, "ros2": 6.0, "browser": 10.0}
"""Seconds guessed for a test of a file not measured, by its markers (the largest that applies; else 0.5)."""


def auto_workers() -> int:
    """Workers for ``-n auto``: two per core, at most one per ROS 2 domain range."""
    return max(1, min(2 * (os.cpu_count() or 1), rosdomains.WORKERS))


def _module_scoped(item: pytest.Item) -> bool:
    info = getattr(item, "_fixtureinfo", None)
    if info is None:
        return False
    for name in info.names_closure:
        defs = info.name2fixturedefs.get(name) or ()
        if any(d.scope in ("module", "class", "package") for d in defs):
            return True
    return False


def _read() -> tuple[set[str], dict[str, float]]:
    data = json.loads(DURATIONS.read_text()) if DURATIONS.exists() else {}
    return set(data.get("modules", ())), dict(data.get("seconds", {}))


def _cost(item: pytest.Item, modules: set[str], seconds: dict[str, float]) -> float:
    """The seconds ``item`` took when measured, else a guess."""
    if item.nodeid in seconds:
        return seconds[item.nodeid]
    if item.nodeid.split("::")[0] in modules:
        return SHORT
    return max([GUESS[m] for m in GUESS if item.get_closest_marker(m) is not None] or [0.5])


def _group(item: pytest.Item) -> str | None:
    """The group ``item`` runs in: its ``xdist_group`` mark's name, else its module when it uses a module-scoped
    fixture, else none (handed out alone)."""
    mark = item.get_closest_marker("xdist_group")
    if mark is not None:
        return str(mark.args[0] if mark.args else mark.kwargs.get("name", "default"))
    return item.nodeid.split("::")[0] if _module_scoped(item) else None


def _join(item: pytest.Item, group: str) -> None:
    """Put ``item`` in ``group`` for ``--dist loadgroup``: the group's name after an ``@`` in its node id, as
    pytest-xdist does itself, but in the form pytest 9 reads (xdist 3.8 sets ``item._nodeid``, which pytest 9 no
    longer has: its own grouping silently does nothing)."""
    if "@" in item.nodeid.rsplit("]", 1)[-1]:
        return
    item._id = coerce_node_id(f"{item.nodeid}@{group}")  # type: ignore[attr-defined]


def arrange(config: pytest.Config, items: list[pytest.Item]) -> None:
    """Skip ``ros2`` tests where rclpy cannot be imported; order the items longest work first (stable: equal costs
    keep the collection's order); in an xdist worker under ``--dist loadgroup``, put each item in its group."""
    no_ros = importlib.util.find_spec("rclpy") is None
    modules, seconds = _read()
    group_of: dict[str, str] = {}
    for item in items:
        if no_ros and item.get_closest_marker("ros2") is not None:
            item.add_marker(pytest.mark.skip(reason="ROS 2 (rclpy) is not installed: scripts/setup.sh installs it"))
        group = _group(item)
        if group is not None:
            group_of[item.nodeid] = group
    cost: dict[str, float] = {}
    first_of: dict[str, int] = {}
    for position, item in enumerate(items):
        key = group_of.get(item.nodeid, item.nodeid)
        cost[key] = cost.get(key, 0.0) + _cost(item, modules, seconds)
        first_of.setdefault(key, position)
    order = {item.nodeid: i for i, item in enumerate(items)}
    items.sort(key=lambda it: (-cost[group_of.get(it.nodeid, it.nodeid)],
                               first_of[group_of.get(it.nodeid, it.nodeid)], order[it.nodeid]))
    if getattr(config.option, "loadgroup", False):  # set in xdist's workers under --dist loadgroup
        for item in items:
            if item.nodeid in group_of:
                _join(item, group_of[item.nodeid])


class DurationStore:
    """``--store-durations``: write the seconds (setup, call and teardown) of every test that took at least
    :data:`KEEP` s to :data:`DURATIONS`, merged with what is there."""

    def __init__(self) -> None:
        self.seconds: dict[str, float] = {}

    @pytest.hookimpl
    def pytest_runtest_logreport(self, report: pytest.TestReport) -> None:
        self.seconds[report.nodeid] = self.seconds.get(report.nodeid, 0.0) + report.duration

    @pytest.hookimpl
    def pytest_sessionfinish(self, session: pytest.Session) -> None:
        if os.environ.get("PYTEST_XDIST_WORKER"):
            return  # the controller writes
        modules, known = _read()
        for grouped, took in self.seconds.items():
            nodeid = grouped.rsplit("@", 1)[0] if "@" in grouped.rsplit("]", 1)[-1] else grouped
            modules.add(nodeid.split("::")[0])
            known.pop(nodeid, None)
            if took >= KEEP:
                known[nodeid] = round(took, 1)
        data = {"modules": sorted(modules), "seconds": dict(sorted(known.items()))}
        DURATIONS.write_text(json.dumps(data, indent=0) + "\n")
