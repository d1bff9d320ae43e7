"""A person driven by a skeleton (issue 30, part 4): joint angles by REP-155 name and the feet frame's pose, put in
place at once (``sim.entities.people.set_joints``, ``sim.inputs.person_joints``, the API's ``_setJointAngle`` and
``_setJointQuaternion`` on a human); the links where forward kinematics puts them on both backends; bad values
refused with nothing changed; a skeleton ends a walk; a recorded skeleton stream replayed bit for bit."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from replaying import resimulate

from sigcore.agent.exceptions import ApiError
from sigcore.api import api_table, call
from sigcore.geometry import quat_from_rpy
from sigcore.record import Recorder
from sigcore.record.replay import load_recording
from sigcore.sim import Simulation
from sigcore.world import WalkPath, Waypoint, parse_world

BACKENDS = ("mujoco", "bullet")
POSE = {"l_y_shoulder": 0.3, "l_p_shoulder": 1.1, "l_r_shoulder": -0.4, "l_elbow": 0.9, "waist": 0.2,
        "r_r_hip": 0.5, "r_knee": -0.8, "r_ankle": 0.3, "y_head": -0.5}


def _sim(tmp_path: Path, body: str, backend: str = "mujoco") -> Simulation:
    path = tmp_path / "w.xml"
    path.write_text(f'<world name="w" timestep="0.002">\n{body}\n</world>\n')
    return Simulation(parse_world(path), backend)


def _angles(sim: Simulation, person: str) -> dict[str, float]:
    return {j: sim.backend.get_joint_angle(person, j) for j in sim.backend.joints(person)}


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_skeleton_puts_every_link_at_its_forward_kinematics(tmp_path: Path, backend: str) -> None:
    """Joint angles and a root pose set at once: after the next steps the wrist, the ankle and the head are where
    the URDF's forward kinematics of those angles puts them, within 1 mm; the joints not named keep their angles."""
    sim = _sim(tmp_path, '<human name="h" pose="0 0 0"/>', backend)
    before = _angles(sim, "h")
    sim.inputs.person_joints("h", {**POSE, "root_x": 1.0, "root_y": -0.5, "root_yaw": 0.7})
    sim.step(10)
    feet = sim.backend.get_pose("h")
    np.testing.assert_allclose(feet[0], [1.0, -0.5, 0.0], atol=1e-9)
    np.testing.assert_allclose(abs(float(np.dot(feet[1], quat_from_rpy(0, 0, 0.7)))), 1.0, atol=1e-9)
    model = sim.world.urdf("h").model
    for link in ("l_wrist", "r_ankle", "head"):
        want_p, want_q = model.link_pose(link, POSE, [1.0, -0.5, 0.0], quat_from_rpy(0, 0, 0.7))
        got_p, got_q = sim.backend.get_pose("h", link)
        np.testing.assert_allclose(got_p, want_p, atol=1e-3)
        assert abs(float(np.dot(got_q, want_q))) == pytest.approx(1.0, abs=1e-6)
    after = _angles(sim, "h")
    for joint, angle in after.items():
        assert angle == pytest.approx(POSE.get(joint, before[joint]), abs=1e-9), joint


def test_the_sig_ros_joint_endpoints_work_on_people(tmp_path: Path) -> None:
    """``_setJointAngle`` and ``_setJointQuaternion`` (the seeds' calls, as a ROS 2 client sends them) pose a
    person's joints: by its own name or by ``name``, from a quaternion about the joint's axis, with ``offset``."""
    sim = _sim(tmp_path, '<human name="h" pose="0 0 0"/><agent name="moderator"/>')
    table = {e.suffix: e for e in api_table()}
    call(sim, table["_setJointAngle"], "h", {"name": "", "joint_name": "l_elbow", "angle": 1.2})
    call(sim, table["_setJointAngle"], "moderator", {"name": "h", "joint_name": "r_elbow", "angle": 0.4})
    axis = np.array([1.0, 0.0, 0.0])  # l_p_shoulder turns about +x
    half = 0.6 / 2
    wxyz = {"qw": math.cos(half), "qx": axis[0] * math.sin(half), "qy": 0.0, "qz": 0.0}
    call(sim, table["_setJointQuaternion"], "h", {"name": "", "joint_name": "l_p_shoulder", **wxyz, "offset": False})
    call(sim, table["_setJointQuaternion"], "h", {"name": "", "joint_name": "l_p_shoulder", **wxyz, "offset": True})
    sim.step(5)
    got = _angles(sim, "h")
    assert (got["l_elbow"], got["r_elbow"]) == (pytest.approx(1.2, abs=1e-9), pytest.approx(0.4, abs=1e-9))
    assert got["l_p_shoulder"] == pytest.approx(1.2, abs=1e-9)


def test_bad_skeletons_are_refused_and_nothing_changes(tmp_path: Path) -> None:
    """An unknown joint, NaN, a string, an angle beyond the joint's limits, a quaternion of zeros: each refused
    naming what is valid; a message with one bad value changes none of its joints."""
    sim = _sim(tmp_path, '<human name="h" pose="0 0 0"/>')
    people = sim.entities.people
    before = _angles(sim, "h")
    for positions, says in (({"l_elbow": 0.5, "l_wristt": 0.1}, "has no joint 'l_wristt'; valid: its REP-155 "
                                                                 "joints waist, r_head"),
                            ({"l_elbow": 0.5, "r_knee": math.nan}, "r_knee of 'h': nan; valid: a finite number"),
                            ({"l_elbow": "bent"}, "'bent' is not a number"),
                            ({"l_elbow": 0.5, "l_knee": 0.5}, "joint 'l_knee' of 'h' turns from -2.5 to 0 rad"),
                            ({"root_x": math.inf}, "root_x of 'h': inf")):
        with pytest.raises(ApiError) as info:
            sim.inputs.person_joints("h", positions)
        assert says in str(info.value), positions
    with pytest.raises(ApiError, match="valid: 4 finite numbers qw qx qy qz"):
        people.joint_quaternion("h", "l_elbow", (0.0, 0.0, 0.0, 0.0))
    with pytest.raises(ApiError, match="no person 'nobody'"):
        people.set_joints("nobody", {"l_elbow": 0.1})
    sim.step(5)
    assert _angles(sim, "h") == before
    np.testing.assert_allclose(sim.backend.get_pose("h")[0], [0, 0, 0], atol=1e-12)


def test_a_skeleton_ends_a_walk_and_a_path(tmp_path: Path) -> None:
    """One motion source at a time: a skeleton stops a walk by velocity and a path at once, and the pose it gave
    stays while stepping on; a walk started afterwards takes over."""
    sim = _sim(tmp_path, '<human name="h" pose="0 0 0"/>')
    people = sim.entities.people
    sim.inputs.person_velocity("h", 1.0, 0.0)
    sim.step(300)
    sim.inputs.person_joints("h", {"l_elbow": 1.0})
    assert not people.walking("h")
    where = sim.backend.get_pose("h")[0].copy()
    sim.step(300)
    np.testing.assert_allclose(sim.backend.get_pose("h")[0], where, atol=1e-12)
    assert sim.backend.get_joint_angle("h", "l_elbow") == pytest.approx(1.0, abs=1e-9)
    sim.inputs.person_path("h", WalkPath(waypoints=(Waypoint(x=3.0, y=0.0),)))
    sim.step(100)
    sim.inputs.person_joints("h", {"root_x": 0.0, "root_y": 0.0})
    assert people.progress("h") is None
    sim.step(100)
    np.testing.assert_allclose(sim.backend.get_pose("h")[0][:2], [0, 0], atol=1e-12)
    sim.inputs.person_velocity("h", 0.5, 0.0)
    sim.step(500)
    assert sim.backend.get_pose("h")[0][0] > 0.4


def test_a_recorded_skeleton_stream_replays_bit_for_bit(tmp_path: Path) -> None:
    """A 30 Hz skeleton stream (a waving arm, the feet turning) is in the input log; replayed, every frame ends bit
    for bit where it was; without its last second it does not."""
    world = tmp_path / "w.xml"
    world.write_text('<world name="w" timestep="0.002"><human name="h" pose="0 0 0"/>'
                     '<object name="ball" shape="sphere" size="0.1" mass="0.3" pose="0.3 0.35 1.9"/></world>')
    sim = Simulation(parse_world(world), "mujoco")
    recorder = Recorder(sim, tmp_path / "bag")
    for step in range(1500):
        if step % 17 == 0:  # about 30 Hz at 2 ms steps
            t = step * 0.002
            sim.inputs.person_joints("h", {"l_p_shoulder": 2.6 + 0.3 * math.sin(6 * t), "l_elbow": 0.4 + 0.4 * t / 3,
                                           "root_yaw": 0.2 * t})
        sim.step()
    recorder.close()
    rec = load_recording(tmp_path / "bag")
    assert len(rec.inputs) == 89 and {i.kind for i in rec.inputs} == {"person_joints"}
    equal, worst, _ = resimulate(rec, tmp_path / "world", rec.inputs)
    assert equal and worst == 0.0
    equal, worst, _ = resimulate(rec, tmp_path / "world", [i for i in rec.inputs if i.step < 1000])
    assert not equal and worst > 0.01
