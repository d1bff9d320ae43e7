"""Spawning and deleting while running through simulation_interfaces, on both backends: a client in another process
spawns a URDF robot, a box and a namespaced spawnable robot while PLAYING (tests/data/sim/world.xml), steps in
lockstep while they fall, finds their endpoints and TF frames, calls their sig_ros services, sends bad requests,
deletes them and sees their endpoints go (clients/spawn.py)."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest

pytest.importorskip("rclpy", reason="rclpy (ROS 2 Jazzy wheels) is not importable")
pytest.importorskip("sigcore_ros2", reason="the sigcore-ros2 plugin is not installed")

from rosproc import ALL_AGENTS, WORLD, client_against  # noqa: E402

pytestmark = pytest.mark.ros2

SIGBOT = Path(__file__).resolve().parents[2] / "worlds" / "models" / "sigbot" / "sigbot.urdf"
OK, NOT_FOUND, OPERATION_FAILED = 1, 2, 4
NAME_NOT_UNIQUE, NO_RESOURCE, NAMESPACE_INVALID, RESOURCE_PARSE_ERROR, MISSING_ASSETS, INVALID_POSE = \
    101, 104, 105, 106, 107, 109
ENTITIES_SPAWN_FAILED = 150
PLAYING, PAUSED = 1, 2
WORLD_ENTITIES = ["bot", "cube", "ball", "heavy", "wall", "man"]
REST = 0.02
"""How far from its resting height [m] a body may be 3 s after it was dropped (it rests within a few mm)."""


@pytest.fixture(scope="module", params=["mujoco", "bullet"])
def out(request: pytest.FixtureRequest, tmp_path_factory: pytest.TempPathFactory) -> Iterator[dict]:
    """What clients/spawn.py saw, per backend (every agent with its sig_ros endpoints, the spawned box too)."""
    yield from client_against(tmp_path_factory.mktemp(f"spawn_{request.param}"), WORLD, "spawn.py", str(SIGBOT),
                              sim_args=("--backend", request.param, *ALL_AGENTS), timeout=240)


def test_spawning_is_announced(out: dict) -> None:
    """get_simulator_features announces spawning, deleting, several at once, resource strings, spawnables and the
    SCOPE_SPAWNED reset, with the formats urdf, sigcore, obj and stl; get_spawnables lists worlds/models' models
    with descriptions and names the sources it did not search."""
    assert {0, 1, 9, 14, 23, 50} <= set(out["features"])
    assert out["formats"] == ["urdf", "sigcore", "obj", "stl"]
    spawnables = out["spawnables"]
    assert spawnables["result"]["result"] == OK and "'/nowhere'" in spawnables["result"]["message"]
    assert {"model://sigbot", "model://box", "model://can"} <= set(spawnables["uris"])
    assert spawnables["described"]


def test_spawned_while_playing_fall_and_rest_on_the_floor(out: dict) -> None:
    """A URDF robot, a box and a spawnable robot spawned in the air while PLAYING keep their names, fall, and rest
    on the floor after 3 s of lockstep steps: the robots' frames at z = 0, the 0.1 m box's centre at 0.05 m (it was
    dropped from 0.8 m)."""
    assert out["state_at_spawn"] == PLAYING
    assert out["rover"] == {"result": OK, "message": "", "name": "rover"}
    assert out["many"]["result"] == OK
    assert out["many"]["results"] == [{"result": OK, "name": "crate"}, {"result": OK, "name": "rover2"}]
    assert out["paused"] == OK and out["step"] == OK
    # How far the crate fell before the pause depends on wall time (a loaded machine may pause after it landed, or
    # while it lands), so only its bounds are asserted: at most where it was dropped (0.8 m), and above the floor's
    # surface. Landing at ~4 m/s, soft contacts let the 0.1 m box sink transiently by a few cm (CI saw its centre
    # at 0.028 m), so the lower bound is the floor (z = 0), not its resting height (0.05 m).
    assert 0.0 < out["z0"]["crate"] <= 0.8 + 1e-6
    assert abs(out["z"]["crate"] - 0.05) < REST
    assert abs(out["z"]["rover"]) < REST and abs(out["z"]["rover2"]) < REST


def test_spawned_agents_have_endpoints_frames_and_services(out: dict) -> None:
    """The spawned robots' joint_states and sig_ros services appear (the namespaced one's under /team1, with its
    drive's cmd_vel and odom), joint states arrive, the box's world -> crate transform is on /tf at its resting
    height, and each robot's get_obj_position service answers with its position."""
    assert out["appeared"] == sorted(["/rover/joint_states", "/rover_get_obj_position", "/rover_setJointAngle",
                                      "/crate_get_obj_position", "/team1/rover2/joint_states",
                                      "/team1/rover2/cmd_vel", "/team1/rover2/odom",
                                      "/team1/rover2_get_obj_position", "/team1/rover2_onRecvMsg"])
    assert out["joint_states"] > 0
    assert out["crate_tf"]["parent"] == "world" and abs(out["crate_tf"]["z"] - 0.05) < REST
    sigros = out["sigros"]
    assert sigros["success"] and abs(sigros["pos_x"] - 1.0) < 0.05 and abs(sigros["pos_y"] - 1.0) < 0.05
    assert out["sigros_ns"]["success"] and abs(out["sigros_ns"]["pos_x"] + 1.0) < 0.05


@pytest.mark.parametrize(("case", "code", "named"), [
    ("malformed", RESOURCE_PARSE_ERROR, "not well-formed"),
    ("unknown", NOT_FOUND, "'nope'"),
    ("taken", NAME_NOT_UNIQUE, "'cube'"),
    ("nan", INVALID_POSE, "nan"),
    ("mesh", MISSING_ASSETS, "/nonexistent/thing.obj"),
    ("joint", RESOURCE_PARSE_ERROR, "'spherical'"),
    ("empty", NO_RESOURCE, "empty"),
    ("namespace", NAMESPACE_INVALID, "'bad ns'"),
    ("frame", INVALID_POSE, "'nowhere'"),
])
def test_bad_requests_are_refused_with_their_code(out: dict, case: str, code: int, named: str) -> None:
    """Each bad spawn request is answered with its standard code and a message naming what was wrong."""
    got = out["bad"][case]
    assert got["result"] == code, got
    assert named in got["message"] and got["name"] == ""


def test_bad_requests_move_nothing_and_the_simulation_goes_on(out: dict) -> None:
    """After the bad requests every entity's pose is bitwise what it was (paused), a taken name with
    allow_renaming gets a free one, a spawn_entities with one bad request spawns the good one and answers
    ENTITIES_SPAWN_FAILED with per-request results, and later spawns work."""
    assert out["unmoved"]
    assert out["renamed"]["result"] == OK and out["renamed"]["name"] not in ("", "cube")
    partial = out["partial"]
    assert partial["result"] == ENTITIES_SPAWN_FAILED and "indices 1" in partial["message"]
    assert partial["results"] == [{"result": OK, "name": "good"}, {"result": NOT_FOUND, "name": ""}]
    assert out["later"]["result"] == OK and abs(out["late_z"] - (0.03 + 1.5)) < 1e-3  # relative to 'cube'
    assert out["replay"]["result"] == OK


def test_deleted_entities_and_their_endpoints_are_gone(out: dict) -> None:
    """Deleting the spawned entities succeeds, their endpoints leave the simulation node's graph, get_entities no
    longer lists them, and deleting one again is NOT_FOUND naming it."""
    assert all(r["result"] == OK for r in out["deleted"].values()), out["deleted"]
    assert out["left"] == []
    assert out["entities"] == WORLD_ENTITIES
    assert out["delete_again"]["result"] == NOT_FOUND and "'rover'" in out["delete_again"]["message"]


def test_reset_scopes_and_stopped(out: dict) -> None:
    """SCOPE_STATE keeps a spawned entity, SCOPE_DEFAULT despawns it; while STOPPED, spawn and delete are refused
    saying how to go on."""
    assert out["reset_state"]["result"] == OK and "late" in out["after_state"]
    assert out["reset_all"]["result"] == OK and out["after_all"] == WORLD_ENTITIES
    for key in ("stopped", "stopped_delete"):
        assert out[key]["result"] == OPERATION_FAILED and "stopped" in out[key]["message"]
