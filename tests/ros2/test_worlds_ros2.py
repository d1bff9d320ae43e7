"""Worlds at run time through simulation_interfaces, on both backends: a client in another process lists the
available worlds (worlds/, --worlds, filters, sources), reads the current one, loads arm6 by path, a world given as
text and the clean-up world by name, sends bad load requests, unloads, and quits (clients/worlds.py). One
simulation process per backend, started with worlds/cleanup.xml and --worlds tests/data/sim/world.xml."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest

pytest.importorskip("rclpy", reason="rclpy (ROS 2 Jazzy wheels) is not importable")
pytest.importorskip("sigcore_ros2", reason="the sigcore-ros2 plugin is not installed")

from rosproc import ALL_AGENTS, WORLD, start_sim, wait_until  # noqa: E402

pytestmark = pytest.mark.ros2

WORLDS = Path(__file__).resolve().parents[2] / "worlds"
CLEANUP, ARM6 = WORLDS / "cleanup.xml", WORLDS / "arm6.xml"
OK, NOT_FOUND, INCORRECT_STATE, OPERATION_FAILED = 1, 2, 3, 4
DEFAULT_SOURCES_FAILED = NO_WORLD_LOADED = 101
UNSUPPORTED_FORMAT, NO_RESOURCE, RESOURCE_PARSE_ERROR, MISSING_ASSETS, UNSUPPORTED_ELEMENTS = 101, 102, 103, 104, 106
STOPPED, PLAYING, PAUSED, NO_WORLD = 0, 1, 2, 4
WORLD_FEATURES = {40, 41, 42, 43, 44, 45}
"""WORLD_LOADING, WORLD_RESOURCE_STRING, WORLD_TAGS, WORLD_UNLOADING, WORLD_INFO_GETTING, AVAILABLE_WORLDS."""


@pytest.fixture(scope="module", params=["mujoco", "bullet"])
def run(request: pytest.FixtureRequest, tmp_path_factory: pytest.TempPathFactory) -> Iterator[dict]:
    """What clients/worlds.py saw, per backend, and whether the simulation then quit cleanly (``exit``); every
    agent with its sig_ros endpoints (the spawned box's are checked)."""
    sim = start_sim(tmp_path_factory.mktemp(f"worlds_{request.param}"), CLEANUP, "--backend", request.param,
                    "--worlds", str(WORLD), *ALL_AGENTS)
    try:
        out = sim.client("worlds.py", str(CLEANUP), str(ARM6), str(WORLD), timeout=240)
        out["exited"] = wait_until(lambda: not sim.alive(), 30.0)
        out["exit"] = sim.proc.returncode
        out["log"] = sim.output()
        yield out
    finally:
        sim.stop()


def names(listing: dict) -> list[str]:
    return [w["name"] for w in listing["worlds"]]


def test_world_features_are_announced(run: dict) -> None:
    """get_simulator_features lists the six world features."""
    assert WORLD_FEATURES <= set(run["features"])


def test_available_worlds_filters_and_sources(run: dict) -> None:
    """get_available_worlds lists worlds/ and --worlds with file URIs, descriptions and tags; a tags filter ALL
    indoor+home keeps only cleanup and cleanup_random, ANY arm+nothing only arm6; an unknown filter mode, a missing
    or remote additional source are OPERATION_FAILED naming it, and continue_on_error answers OK with the problem in
    the message."""
    listing = run["all"]
    assert listing["result"] == OK, listing
    assert {"cleanup", "arm6", "coretest"} <= set(names(listing))
    by_name = {w["name"]: w for w in listing["worlds"]}
    assert by_name["cleanup"]["uri"] == CLEANUP.as_uri() and by_name["coretest"]["uri"] == WORLD.as_uri()
    assert by_name["cleanup"]["tags"] == ["indoor", "home", "robocup"] and by_name["cleanup"]["description"]
    assert names(run["filtered"]) == ["cleanup", "cleanup_random"] and names(run["any"]) == ["arm6"]
    assert run["bad_mode"]["result"] == OPERATION_FAILED and "filter_mode 7" in run["bad_mode"]["message"]
    missing = run["missing_source"]
    assert missing["result"] == OPERATION_FAILED and "/no/such/worlds" in missing["message"]
    assert missing["worlds"] == []
    kept = run["missing_continue"]
    assert kept["result"] == OK and "/no/such/worlds" in kept["message"] and "cleanup" in names(kept)
    remote = run["remote_source"]
    assert remote["result"] == OPERATION_FAILED and "only local paths and file:// URIs" in remote["message"]
    assert run["file_uri_source"]["result"] == OK and "coretest" in names(run["file_uri_source"])


def test_current_world_is_the_one_running(run: dict) -> None:
    """get_current_world names the clean-up world with its file URI, tags and description."""
    cur = run["current"]
    assert cur["result"] == OK and cur["name"] == "cleanup" and cur["uri"] == CLEANUP.as_uri()
    assert cur["tags"] == ["indoor", "home", "robocup"] and cur["text"] == ""


def test_load_world_by_path_replaces_endpoints_and_restarts_the_clock(run: dict) -> None:
    """load_world arm6 by path: OK, STOPPED, only arm_0; robot_000's endpoints leave the graph and arm_0's appear
    and answer; /clock goes from the clean-up world's time back to exactly 0 and advances again once PLAYING."""
    assert run["robot_000_before"] == sorted(["/robot_000_get_obj_position", "/robot_000/cmd_vel",
                                              "/robot_000/joint_states"])
    assert run["load_arm6"] == {"result": OK, "message": "", "name": "arm6"}
    assert run["state_after_load"] == STOPPED and run["entities_arm6"] == ["arm_0"]
    assert run["robot_000_after"] == [] and run["arm_0"] == ["/arm_0/joint_states", "/arm_0_get_obj_position"]
    assert run["arm_position"] is not None and run["arm_position"]["success"]
    assert run["clock_before"] > 0.2 and run["clock_after_load"] == 0.0
    assert run["current_arm6"]["uri"] == ARM6.as_uri()
    assert run["play"]["result"] == OK and run["clock_playing"] > 0.2


def test_load_world_from_text_follows_its_timestep(run: dict) -> None:
    """A world given as resource_string loads STOPPED, a step request still pending then fails naming the world
    unloaded, the new object's sig_ros endpoints appear, get_current_world returns the text, and 100 steps of its
    0.005 s timestep put /clock at exactly 0.5 s."""
    assert run["pause"]["result"] == OK
    assert run["load_text"] == {"result": OK, "message": "", "name": "tiny"}
    pending = run["pending_step"]
    assert pending["result"] == OPERATION_FAILED and "'arm6' was unloaded" in pending["message"], pending
    assert run["state_text"] == STOPPED and run["entities_text"] == ["crate"] and run["crate_endpoint"]
    cur = run["current_text"]
    assert cur["name"] == "tiny" and cur["uri"] == "" and "<world name=\"tiny\"" in cur["text"]
    assert cur["tags"] == ["test"] and cur["description"] == "a box on the floor"
    assert run["step_text"]["result"] == OK and run["clock_text"] == 0.5


@pytest.mark.parametrize(("case", "code", "named"), [
    ("empty", NO_RESOURCE, "neither uri nor resource_string"),
    ("sdf", UNSUPPORTED_FORMAT, "<sdf>"),
    ("malformed", RESOURCE_PARSE_ERROR, "not well-formed"),
    ("urdf", MISSING_ASSETS, "/nonexistent/r.urdf"),
    ("urdf_ignore", MISSING_ASSETS, "never ignores assets"),
    ("element", UNSUPPORTED_ELEMENTS, "never ignores elements"),
    ("element_strict", UNSUPPORTED_ELEMENTS, "<spaceship>"),
    ("name", NOT_FOUND, "'no_such_world'"),
])
def test_bad_load_requests_are_refused_with_their_code(run: dict, case: str, code: int, named: str) -> None:
    """Each bad load_world request is answered with its LoadWorld code and a message naming what was wrong."""
    got = run["bad"][case]
    assert got["result"] == code and named in got["message"], got


def test_bad_load_requests_leave_the_world_running(run: dict) -> None:
    """After the bad requests the world given as text is still the current one, with the same entities."""
    assert run["current_after_bad"]["name"] == "tiny" and run["current_after_bad"]["text"] == \
        run["current_text"]["text"]
    assert run["entities_after_bad"] == ["crate"]


def test_unloaded_state_refuses_what_needs_a_world(run: dict) -> None:
    """unload_world: OK, then NO_WORLD, no current world, no entities, /clock at 0, /tf_static and /sigcore/scene
    still there and the crate's endpoints gone; PLAYING, steps and spawns are refused
    naming load_world; a second unload is NO_WORLD_LOADED; load_world "cleanup" by name brings robot_000's endpoints
    back, STOPPED."""
    assert run["unload"]["result"] == OK and run["state_unloaded"] == NO_WORLD
    assert run["current_unloaded"]["result"] == NO_WORLD_LOADED and run["entities_unloaded"] == []
    assert run["clock_unloaded"] == 0.0 and run["graph_unloaded"] == ["/sigcore/scene", "/tf_static"]
    for key in ("play_unloaded", "step_unloaded", "spawn_unloaded"):
        assert run[key]["result"] == INCORRECT_STATE and "load_world" in run[key]["message"], run[key]
    assert run["unload_again"]["result"] == NO_WORLD_LOADED
    assert run["load_cleanup"]["result"] == OK and run["state_cleanup"] == STOPPED
    assert run["robot_000_back"] == run["robot_000_before"]
    assert run["robot_position"] is not None and run["robot_position"]["success"]
    assert run["current_cleanup"]["uri"] == CLEANUP.as_uri()


def test_simulator_survives_and_quits_cleanly(run: dict) -> None:
    """The simulation still answered at the end, and QUITTING ended it with exit code 0."""
    assert run["state_end"] == STOPPED and run["quit"]["result"] == OK
    assert run["exited"] and run["exit"] == 0, run["log"][-3000:]
