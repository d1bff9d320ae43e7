"""The viewer service 'referee' through the agent API: Referee/text/points messages, errors that crash nothing."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
from referee_worlds import BOXES, ITEMS, MODERATOR, make_sim, run_for
from sigcore_referee import Referee, RefereeEvent

from sigcore.api import api_table
from sigcore.api.call import call
from sigcore.sim import Simulation

ENTRIES = {e.suffix: e for e in api_table()}


def _call(sim: Simulation, suffix: str, request: dict[str, Any], agent: str = "moderator_0") -> dict[str, Any]:
    result = call(sim, ENTRIES[suffix], agent, request)
    assert isinstance(result, dict)
    return result


@pytest.fixture
def sim(tmp_path: Path) -> Simulation:
    """A service-only referee (no rules attribute) and a moderator connected to it."""
    s = make_sim(tmp_path, BOXES + ITEMS + MODERATOR, "")
    assert _call(s, "_connect_to_service", {"service_name": "referee"})["connected"]
    return s


def _referee(sim: Simulation) -> Referee:
    ref = sim.features["referee"]
    assert isinstance(ref, Referee)
    return ref


def test_check_service_sees_the_referee(sim: Simulation) -> None:
    """_check_service answers True for 'referee' and False for a service nobody offers."""
    assert _call(sim, "_check_service", {"service_name": "referee"})["connected"] is True
    assert _call(sim, "_check_service", {"service_name": "scoreboard"})["connected"] is False


def test_message_adds_points_and_records_the_sender(sim: Simulation) -> None:
    """A well-formed message adds its points and records a 'message' event with the sender."""
    run_for(sim, 0.1)
    reply = _call(sim, "_send_msg_to_srv", {"name": "referee", "msg": "Referee/collision with table_0/-100"})
    assert reply["success"] and reply["ok"]
    _call(sim, "_send_msg_to_srv", {"name": "referee", "msg": "Referee/well done/+30"})
    ref = _referee(sim)
    assert ref.score == -70
    assert ref.events[0] == RefereeEvent(0.1, "message", "moderator_0: collision with table_0", -100)


@pytest.mark.parametrize("text", ["Collision/-100", "Referee/collision", "Referee/collision/-1.5",
                                  "Referee/collision/lots", "Referee//10"])
def test_malformed_text_gets_an_error_reply(sim: Simulation, text: str) -> None:
    """A malformed text is answered success=False with the expected format; nothing is scored; steps go on."""
    reply = _call(sim, "_send_msg_to_srv", {"name": "referee", "msg": text})
    assert reply["success"] is False and reply["ok"] is False
    assert "expected 'Referee/<text>/<points>'" in reply["message"]
    assert _referee(sim).events == []
    run_for(sim, 0.1)
    assert sim.step_count == 50


def test_unknown_service_gets_an_error_reply(sim: Simulation) -> None:
    """Connecting or sending to a service that does not exist is refused, listing the services."""
    for suffix, request in [("_connect_to_service", {"service_name": "Referree"}),
                            ("_send_msg_to_srv", {"name": "Referree", "msg": "Referee/x/1"})]:
        reply = _call(sim, suffix, request)
        assert reply["success"] is False and "no service 'Referree'; services: referee" in reply["message"]


def test_sender_must_connect_first(sim: Simulation) -> None:
    """An agent that did not connect is refused (core rule), and nothing is scored."""
    reply = _call(sim, "_send_msg_to_srv", {"name": "referee", "msg": "Referee/x/1"}, agent="can_0")
    assert reply["success"] is False and "not connected" in reply["message"]
    assert _referee(sim).score == 0


def test_service_only_referee_watches_nothing(sim: Simulation) -> None:
    """Without rules="cleanup" no collision observer is attached and items are not judged."""
    assert sim.events.subscriptions("collision") == ()
    sim.entities["can_0"].set_position([0.0, 0.0, 0.6])
    run_for(sim, 2.0)
    assert _referee(sim).events == [] and _referee(sim).items is None


def test_service_name_is_configurable(tmp_path: Path) -> None:
    """service="Referee" offers the sig_ros spelling instead."""
    s = make_sim(tmp_path, BOXES + ITEMS + MODERATOR, 'service="Referee"')
    assert set(s.features.services) == {"Referee"}
