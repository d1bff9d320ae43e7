"""The sig_ros services completed: the manual's names, the connection check, service names ignoring case."""

from __future__ import annotations

from typing import Any

import pytest

from sigcore.api import api_table, call
from sigcore.api.table import ApiEntry
from sigcore.sim import Simulation


def _entry(suffix: str) -> ApiEntry:
    return next(e for e in api_table() if e.suffix == suffix)


def _inbox(sim: Simulation, name: str = "referee") -> list[tuple[str, str]]:
    got: list[tuple[str, str]] = []
    sim.features.register_service(name, lambda sender, text: got.append((sender, text)))
    return got


def _call(sim: Simulation, suffix: str, agent: str, **request: Any) -> dict[str, Any]:
    out = call(sim, _entry(suffix), agent, request)
    assert isinstance(out, dict)
    return out


def test_send_msg_to_service_is_send_msg_to_srv(sim: Simulation) -> None:
    """_send_msg_to_service (the manual's name) delivers like _send_msg_to_srv and is refused the same way."""
    got = _inbox(sim)
    r = _call(sim, "_send_msg_to_service", "moderator", name="referee", msg="Referee/early/1")
    assert not r["success"] and not r["ok"] and "moderator_connect_to_service first" in r["message"]
    assert _call(sim, "_connect_to_service", "moderator", service_name="referee")["connected"]
    assert _call(sim, "_send_msg_to_service", "moderator", name="referee", msg="Referee/a/1")["ok"]
    assert _call(sim, "_send_msg_to_srv", "moderator", name="referee", msg="Referee/b/2")["ok"]
    assert got == [("moderator", "Referee/a/1"), ("moderator", "Referee/b/2")]
    assert _entry("_send_msg_to_service").ros_type == _entry("_send_msg_to_srv").ros_type


def test_check_service_answers_whether_this_agent_is_connected(sim: Simulation) -> None:
    """_check_service is false until this agent connects, true after, and stays false for another agent."""
    _inbox(sim)
    assert _call(sim, "_check_service", "bot", service_name="referee") == {
        "connected": False, "success": True, "message": ""}
    _call(sim, "_connect_to_service", "bot", service_name="referee")
    assert _call(sim, "_check_service", "bot", service_name="referee")["connected"] is True
    assert _call(sim, "_check_service", "moderator", service_name="referee")["connected"] is False


def test_service_names_ignore_case(sim: Simulation) -> None:
    """sig_ros's 'Referee' reaches sigcore's 'referee' for connect, check and send; the message is delivered."""
    got = _inbox(sim)
    assert _call(sim, "_connect_to_service", "moderator", service_name="Referee")["connected"]
    assert _call(sim, "_check_service", "moderator", service_name="REFEREE")["connected"]
    assert _call(sim, "_send_msg_to_srv", "moderator", name="referee", msg="Referee/x/5")["ok"]
    assert got == [("moderator", "Referee/x/5")]


def test_unknown_service_lists_the_valid_names(sim: Simulation) -> None:
    """An unknown service name is refused by check, connect and send, naming the services that exist."""
    _inbox(sim)
    _inbox(sim, "judge")
    for suffix, field in (("_check_service", "service_name"), ("_connect_to_service", "service_name"),
                          ("_send_msg_to_service", "name")):
        r = _call(sim, suffix, "bot", **{field: "Referree"})
        assert not r["success"]
        assert r["message"] == ("no service 'Referree'; services: judge, referee (names are compared ignoring "
                                "case)"), suffix


def test_names_differing_only_in_case(sim: Simulation) -> None:
    """With services 'referee' and 'Referee', an exact name picks its own; any other spelling is refused as
    ambiguous, naming both."""
    lower, upper = _inbox(sim), _inbox(sim, "Referee")
    _call(sim, "_connect_to_service", "bot", service_name="Referee")
    assert _call(sim, "_send_msg_to_srv", "bot", name="Referee", msg="Referee/u/1")["ok"]
    assert (lower, upper) == ([], [("bot", "Referee/u/1")])
    r = _call(sim, "_connect_to_service", "bot", service_name="REFEREE")
    assert not r["success"] and "matches Referee, referee, which differ only in case" in r["message"]


def test_collision_state_of_main_part(sim: Simulation) -> None:
    """_get_collision_state_of_main_part equals _get_collision_state with part main: true for a box on the floor,
    false for a ball held in the air; a bare agent must name an entity."""
    sim.agent("ball").set_dynamics_mode(False)
    sim.agent("ball").set_position((-1.0, 1.0, 1.5))
    sim.step(5)
    for agent, name, expected in (("heavy", "", True), ("moderator", "heavy", True), ("ball", "", False),
                                  ("bot", "ball", False)):
        r = _call(sim, "_get_collision_state_of_main_part", agent, name=name)
        assert r["success"] and r["collision_state"] is expected, (agent, name)
        same = _call(sim, "_get_collision_state", agent, name=name, part="main")
        assert same["collision_state"] is expected
    r = _call(sim, "_get_collision_state_of_main_part", "moderator", name="")
    assert not r["success"] and "bare agent" in r["message"]


@pytest.mark.parametrize("suffix", ["_send_msg_to_service", "_get_collision_state_of_main_part"])
def test_manual_names_are_in_the_table_for_every_kind(suffix: str) -> None:
    """The manual's names exist for every kind of agent, as services answering success and message."""
    entry = _entry(suffix)
    assert entry.direction == "service" and entry.kinds == {"robot", "object", "human", "agent"}
    assert entry.response is not None and {"success", "message"} <= set(entry.response.model_fields)
