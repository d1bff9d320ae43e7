"""The ROS 2 transport end to end: a simulation process and plain rclpy client processes (tests/ros2/clients/).

One real-time simulation of tests/data/sim/world.xml serves the whole module; tests touch different entities.
"""

from __future__ import annotations

import importlib
import math

import numpy as np
import pytest

pytest.importorskip("rclpy", reason="rclpy (ROS 2 Jazzy wheels) is not importable")
pytest.importorskip("sigcore_ros2", reason="the sigcore-ros2 plugin is not installed")

from rosproc import WORLD, SimProcess  # noqa: E402

from sigcore.api import api_table  # noqa: E402
from sigcore.geometry import quat_from_rpy, quat_mul, quat_rotate  # noqa: E402
from sigcore.world import parse_world  # noqa: E402

pytestmark = pytest.mark.ros2

DT = 0.002


def _exists(ros_type: str, kind: str) -> bool:
    if "/" in ros_type:
        return True
    return hasattr(importlib.import_module(f"sigcore_msgs.{kind}"), ros_type)


def expected_endpoints() -> tuple[dict[str, str], dict[str, str]]:
    """Topics and services the world must have with ``sigros_agents=all``, with their types, from the API table."""
    world = parse_world(WORLD)
    lidars = {a.name for a in world.agents if a.kind == "robot" and a.lidars}
    topics: dict[str, str] = {}
    services: dict[str, str] = {}
    for agent in world.agents:
        for e in api_table():
            if agent.kind not in e.kinds or (e.suffix == "_scan" and agent.name not in lidars):
                continue
            kind = "srv" if e.direction == "service" else "msg"
            if not _exists(e.ros_type, kind):
                continue  # a type newer than the built sigcore_msgs (the transport warns and leaves it out)
            full = e.ros_type if "/" in e.ros_type else f"sigcore_msgs/{kind}/{e.ros_type}"
            (services if kind == "srv" else topics)[f"/{e.name_for(agent.name)}"] = full
    for e in api_table():  # the shared endpoints: every function whose request names its entity, by name
        if e.direction != "publish" and e.request is not None and "name" in e.request.model_fields \
                and e.ros_type != "SendMsgToSrv" and _exists(e.ros_type, "srv" if e.direction == "service" else "msg"):
            kind = "srv" if e.direction == "service" else "msg"
            full = e.ros_type if "/" in e.ros_type else f"sigcore_msgs/{kind}/{e.ros_type}"
            (services if kind == "srv" else topics)[f"/sigcore/sigros/{e.suffix.lstrip('_')}"] = full
    topics.update({"/clock": "rosgraph_msgs/msg/Clock", "/tf": "tf2_msgs/msg/TFMessage",
                   "/tf_static": "tf2_msgs/msg/TFMessage", "/sigcore/ready": "std_msgs/msg/Bool",
                   "/bot/cmd_vel": "geometry_msgs/msg/Twist", "/bot/odom": "nav_msgs/msg/Odometry",
                   "/bot/joint_states": "sensor_msgs/msg/JointState", "/bot/scan": "sensor_msgs/msg/LaserScan"})
    for name in ("get_simulator_features", "get_entities", "get_entity_state", "set_entity_state",
                 "get_entities_states", "get_entity_info", "set_entity_info", "get_entity_bounds",
                 "get_named_poses", "get_named_pose_bounds", "spawn_entity", "delete_entity",
                 "get_simulation_state", "set_simulation_state", "reset_simulation", "step_simulation"):
        camel = "".join(p.capitalize() for p in name.split("_"))
        services[f"/{name}"] = f"simulation_interfaces/srv/{camel}"
    services["/simulate_steps/_action/send_goal"] = "simulation_interfaces/action/SimulateSteps_SendGoal"
    return topics, services


def _ok(res: dict) -> bool:
    return res is not None and res["success"] is True and res["message"] == ""


def test_graph_has_every_endpoint_with_its_type(sim_proc: SimProcess) -> None:
    """Another process finds every sig_ros topic/service, the idiomatic topics and simulation_interfaces, typed."""
    topics, services = expected_endpoints()
    graph = sim_proc.client("graph.py", str(len(topics) + len(services)))
    missing = [f"{n} ({t})" for n, t in topics.items() if t not in graph["topics"].get(n, [])]
    missing += [f"{n} ({t})" for n, t in services.items() if t not in graph["services"].get(n, [])]
    assert not missing, f"{len(missing)} endpoints missing or mistyped, e.g. {missing[:10]}"
    assert len(services) > 100 and len(topics) > 150


def test_every_sigros_service_for_a_robot_and_an_object(sim_proc: SimProcess) -> None:
    """Each sig_ros service of bot and cube answers, and agrees with the ground truth of get_entity_state."""
    out = sim_proc.client("services.py")
    truth = out["truth"]["cube"]["state"]["pose"]["position"]
    for agent in ("bot", "cube"):
        get = {k.removeprefix(f"/{agent}"): v for k, v in out.items() if k.startswith(f"/{agent}_")}
        time_res, ents, cube_pos, own_pos = get["_get_time"][0], get["_get_entities"][0], *get["_get_obj_position"]
        assert _ok(time_res) and time_res["time"] > 0
        assert ents["entities_names"] == ["bot", "cube", "ball", "heavy", "wall", "man", "moderator"]
        assert ents["length"] == 7
        assert _ok(cube_pos)
        assert cube_pos["pos_x"] == pytest.approx(truth["x"], abs=1e-3)
        assert cube_pos["pos_y"] == pytest.approx(truth["y"], abs=1e-3)
        assert cube_pos["pos_z"] == pytest.approx(0.03, abs=2e-3)
        own_truth = out["truth"][agent]["state"]["pose"]["position"]
        assert own_pos["pos_x"] == pytest.approx(own_truth["x"], abs=1e-3)
        assert _ok(get["_get_parts_position"][0]) and get["_get_parts_position"][0]["pos_z"] > 0.05
        assert _ok(get["_get_joint_position"][0])
        rot = get["_get_rotation"][0]
        assert _ok(rot) and rot["qw"] ** 2 + rot["qx"] ** 2 + rot["qy"] ** 2 + rot["qz"] ** 2 == pytest.approx(1)
        assert get["_get_angle_rotation"][0]["angle"] == pytest.approx(math.pi / 2)
        assert _ok(get["_get_joint_angle"][0])
        joints = get["_get_all_joint_angles"][0]
        assert set(joints["joint_name"]) >= {"shoulder_joint", "elbow_joint"}
        assert joints["length"] == len(joints["angle"])
        assert get["_get_mass"][0]["mass"] == pytest.approx(0.2)
        assert _ok(get["_get_angular_velocity"][0])
        assert get["_get_collision_state"][0]["collision_state"] is True  # the cube rests on the floor
        assert _ok(get["_is_grasped"][0]) and get["_is_grasped"][0]["answer"] is False
        assert get["_check_service"][0]["connected"] is False  # no referee in this world
        assert get["_connect_to_service"][0]["success"] is False
        assert "no service 'referee'" in get["_connect_to_service"][0]["message"]
        assert get["_send_msg_to_srv"][0]["success"] is False
    grasp = out["/bot_grasp_obj"][0]
    assert grasp["success"] is False and grasp["ok"] is False and grasp["message"]


def test_every_sigros_topic_has_its_effect(sim_proc: SimProcess) -> None:
    """Publishing each sig_ros command topic changes the simulation as documented (seen through services)."""
    out = sim_proc.client("topics.py", timeout=120)
    assert out["setGravityMode+setPosition"] == pytest.approx([-1.0, 1.0, 1.0], abs=0.02)
    assert out["setVelocity_z"] > 1.1
    assert out["setAngularVelocity"]["v_z"] == pytest.approx(3.0, abs=0.3)
    half = math.sqrt(0.5)
    assert abs(out["setRotation"]["qz"]) == pytest.approx(math.sin(0.25), abs=1e-3)
    assert abs(out["setAxisAndAngle"]["qz"]) == pytest.approx(math.sin(0.5), abs=1e-3) != half
    assert out["setMass"]["mass"] == pytest.approx(7.5)
    for topic, (vx, wz) in out["forces"].items():
        assert (wz if topic == "_setTorque" else vx) > 0.01, f"{topic} had no effect along +x: {vx}, {wz}"
    assert out["setDynamicsMode_off_z"] == pytest.approx(0.8, abs=0.01)
    assert out["setDynamicsMode_on_z"] < 0.2  # falls once dynamics is back on
    assert out["setCollisionEnable_off_z"] < 0.0
    assert out["setJointAngle"]["angle"] == pytest.approx(0.7, abs=0.05)
    assert out["setJointQuaternion"]["angle"] == pytest.approx(0.4, abs=0.05)
    assert out["setJointVelocity_delta"] > 0.2
    assert out["setWheelVelocity_dx"] > 0.1
    assert _ok(out["grasp"]) and out["grasp"]["ok"] is True, out["cube_at_grasp"]
    assert out["is_grasped_after_grasp"]["answer"] is True
    assert out["is_grasped_after_release"]["answer"] is False
    log = sim_proc.output()
    for topic in ("_setWheel ", "_setOwner", "_addJointTorque", "_releaseObj"):
        assert f"bot{topic}" not in log, f"bot{topic} was refused:\n{log[-2000:]}"


def test_collision_and_text_message_topics(sim_proc: SimProcess) -> None:
    """A new contact appears on <agent>_onCollisionMsg; a text sent with _sendMsg on <to>_onRecvMsg."""
    out = sim_proc.client("events.py")
    assert {"name": "ball", "part": "main"} in out["collisions"], out["collisions"]
    assert {"sender": "bot", "content": "hello moderator"} in out["texts"]


def test_cmd_vel_drives_odom_and_tf_follow(sim_proc: SimProcess) -> None:
    """cmd_vel moves the robot; odom and /tf follow the ground truth; everything is stamped with sim time."""
    out = sim_proc.client("drive.py")
    assert out["truth_dx"] > 0.4  # 0.4 m/s for about 2 s of real (= simulated) time
    assert out["odom_dx"] == pytest.approx(out["truth_dx"], rel=0.1, abs=0.05)
    assert out["odom_frames"] == ["odom", "base_link"]
    tf = out["tf_last"]
    assert tf["header"]["frame_id"] == "odom" and tf["child_frame_id"] == "base_link"
    assert tf["transform"]["translation"]["x"] == pytest.approx(out["odom_last_x"], abs=0.02)
    for stamps, period in ((out["odom_stamps"], 0.02), (out["tf_stamps"], 0.02), (out["scan_stamps"], 0.1)):
        assert all(b > a for a, b in zip(stamps, stamps[1:], strict=False)), stamps
        assert all(abs(s / period - round(s / period)) < 1e-6 for s in stamps), stamps  # sim-time steps
    clock = out["clock"]
    assert len(clock) > 10 and all(b >= a for a, b in zip(clock, clock[1:], strict=False))
    assert all(abs(c / DT - round(c / DT)) < 1e-6 for c in clock)


def test_cmd_vel_walks_a_person_whose_frames_follow(sim_proc: SimProcess) -> None:
    """Twist on /man/cmd_vel from another process walks the person forward (its knees bend and straighten on /tf);
    a speed out of range is refused and the walk goes on; without messages it stands after 0.5 s."""
    out = sim_proc.client("walk.py")
    dx, dy = out["walked"][0] - out["start"][0], out["walked"][1] - out["start"][1]
    assert dx > 0.6 and abs(dy) < 1e-6  # 0.8 m/s for about 1.5 s of real (= simulated) time
    assert out["after_refusal"][0] > out["walked"][0]  # still walking at 0.8 m/s
    assert out["still"] == out["stood"]
    knees = out["knees"]
    assert len(knees) > 5 and max(knees) - min(knees) > 0.1
    assert {"l_knee_man", "r_ankle_man", "p_head_man", "man"} <= set(out["frames"])  # movable joints' children


def test_a_path_on_man_path_walks_the_person_and_bad_paths_are_refused(sim_proc: SimProcess) -> None:
    """A nav_msgs/Path from another process walks the person through its poses (0.5 m, a quarter turn, 0.5 m at
    1.0 m/s: about 2 s), ending within 1 cm of the last; a path through the wall, in another frame, with no poses or
    with a NaN is refused and the person stays there."""
    out = sim_proc.client("path.py", timeout=60)
    assert out["start"] == pytest.approx([-2.0, -1.5], abs=1e-6)
    assert out["arrived"] == pytest.approx([-1.5, -1.0], abs=0.01)
    assert 1.5 < out["took"] < 10.0  # real time paced: 2.05 s simulated, with wide margins for a loaded machine
    assert out["after"] == pytest.approx(out["arrived"], abs=1e-6)


def _chain(frames: dict, child: str) -> tuple[np.ndarray, np.ndarray]:
    """The pose in ``world`` of TF frame ``child``, composed from ``frames`` (child -> [parent, xyz, wxyz])."""
    xyz, wxyz = np.zeros(3), np.array([1.0, 0.0, 0.0, 0.0])
    while child != "world":
        parent, t, q = frames[child]
        xyz, wxyz = np.asarray(t) + quat_rotate(np.asarray(q), xyz), quat_mul(np.asarray(q), wxyz)
        child = parent
    return xyz, wxyz


def test_a_skeleton_stream_poses_the_person_and_bad_ones_are_refused(sim_proc: SimProcess) -> None:
    """A JointState stream on /man/skeleton from another process moves the person's joints and feet frame: the
    wrist's and the head's TF (composed from /tf and /tf_static) are where forward kinematics of the commanded angles
    puts them, within 1 mm; skeletons with lengths that differ, an unknown joint, a NaN or a joint named twice are
    refused and the pose stays."""
    out = sim_proc.client("skeleton.py", timeout=60)
    root = out["root"]
    feet = ([root["root_x"], root["root_y"], 0.0], quat_from_rpy(0.0, 0.0, root["root_yaw"]))
    model = parse_world(WORLD).urdf("man").model
    for link in ("l_wrist", "head"):
        want, _ = model.link_pose(link, out["pose"], *feet)
        got, _ = _chain(out["posed"], f"{link}_man")
        np.testing.assert_allclose(got, want, atol=1e-3)
        np.testing.assert_allclose(_chain(out["after"], f"{link}_man")[0], got, atol=1e-9)


def test_joint_states_scan_and_static_frames(sim_proc: SimProcess) -> None:
    """joint_states name every movable joint; the LaserScan is well formed; /tf_static is latched."""
    out = sim_proc.client("drive.py")
    js = out["joints"]
    assert {"wheel_l_joint", "wheel_r_joint", "shoulder_joint", "elbow_joint"} <= set(js["name"])
    assert len(js["position"]) == len(js["name"]) == len(js["velocity"])
    scan = out["scan"]
    assert out["scan_len"] == 180 and scan["header"]["frame_id"] == "laser_link"
    assert scan["angle_increment"] == pytest.approx((scan["angle_max"] - scan["angle_min"]) / 179)
    assert scan["range_min"] == pytest.approx(0.05) and scan["range_max"] == pytest.approx(8.0)
    assert out["sigros_scans"] > 0
    assert ["world", "odom"] in out["static"] and ["base_link", "laser_link"] in out["static"]


def test_qos_follows_rep_2003(sim_proc: SimProcess) -> None:
    """/tf_static and readiness are transient local; sensor data and /clock reliable and volatile."""
    qos = sim_proc.client("drive.py")["qos"]
    assert "TRANSIENT_LOCAL" in qos["/tf_static"][1] and "TRANSIENT_LOCAL" in qos["/sigcore/ready"][1]
    for topic in ("/clock", "/bot/scan", "/tf"):
        assert "RELIABLE" in qos[topic][0] and "VOLATILE" in qos[topic][1]


def test_fuzzed_bad_requests_get_errors_and_the_simulation_runs_on(sim_proc: SimProcess) -> None:
    """Every bad request is answered with an error saying what was wrong; the simulation keeps stepping."""
    out = sim_proc.client("fuzz.py", timeout=90)
    for a in out["answers"]:
        res = a["response"]
        assert res is not None, f"no answer to {a['call']}"
        if "result" in res:  # simulation_interfaces
            assert res["result"]["result"] != 1 and res["result"]["error_message"], a
        else:
            assert res["success"] is False and res["message"], a
    assert out["t1"] > out["t0"] and len(out["clock"]) >= 5
    assert sim_proc.alive()
    log = sim_proc.output()
    assert "ball_setPosition refused" in log and log.count("ball_setPosition refused") == 1  # logged once
