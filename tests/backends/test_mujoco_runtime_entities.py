"""MuJoCo only: adding and removing entities while running keeps every other body's state and trajectory bit for
bit.

The backend-independent behaviour (falling, resting, grasping, reset, refusals) is in ``test_conformance_spawn.py``;
here is what only the MuJoCo backend promises (``carry.py``): the state carried over exactly, the same trajectory as
a run without the spawn step by step, no element left behind.
"""

from __future__ import annotations

from pathlib import Path

import mujoco
import numpy as np
import pytest
from sigcore_backend_mujoco import MujocoBackend

from sigcore.errors import BackendError
from sigcore.world import World, parse_world
from sigcore.world.models import Object, Pose, Robot

ROOT = Path(__file__).resolve().parents[2]
CLEANUP = ROOT / "worlds" / "cleanup.xml"
MUG = ROOT / "tests" / "data" / "worlds" / "models" / "mug.obj"
TABLE = ROOT / "worlds" / "models" / "table" / "table.urdf"
FAR = (0.0, -0.8, 0.6)
"""Where spawned things appear: above the floor of the corridor, more than 1 m from anything else [m]."""

STEPS = 600


def _cleanup() -> World:
    return parse_world(CLEANUP)


def _spawnable(world: World, kind: str) -> tuple[Object | Robot, ...]:
    """What to add to the clean-up world: one entity of ``kind``, or several in one call (``many``)."""
    box = Object(name="box_9", shape="box", size=(0.2, 0.2, 0.2), pose=Pose(xyz=FAR), graspable=True)
    if kind == "box":
        return (box,)
    if kind == "mesh":
        return (Object(name="mug_9", mesh=MUG, pose=Pose(xyz=FAR), mass=0.3),)
    if kind == "urdf":
        return (Object(name="table_9", urdf=TABLE, static=True, pose=Pose(xyz=(0.0, -0.8, 0.0))),)
    robot = world.agent("robot_000")
    assert isinstance(robot, Robot)
    bot = robot.model_copy(update={"name": "robot_009", "pose": Pose(xyz=(0.5, -1.0, 0.0)), "lidars": ()})
    if kind == "robot":
        return (bot,)
    return (box.model_copy(update={"pose": Pose(xyz=(-1.0, -0.8, 0.6))}), bot)


def _busy(backend: MujocoBackend) -> None:
    """Give the world run-time changes that the backend keeps in the model and its own bookkeeping."""
    backend.set_joint_velocity("robot_000", "wheel_l_joint", 2.0)
    backend.set_joint_velocity("robot_000", "wheel_r_joint", 3.0, max_torque=15.0)
    backend.set_joint_target("robot_000", "l_shoulder_pitch_joint", -0.6)
    backend.set_joint_velocity("robot_000", "r_elbow_joint", 0.4, max_torque=30.0)
    backend.attach("robot_000", "l_hand_link", "can_0")
    backend.set_mass("petbottle_1", 0.9)
    backend.set_gravity_mode("apple_2", False)
    backend.set_collision_mode("trashbox_1", False)
    backend.set_pose("table_1", np.array([1.5, 1.8, 0.0]))
    backend.set_dynamics_mode("trashbox_2", False)
    backend.apply_wrench("man_0", None, np.array([5.0, 0.0, 0.0]), np.zeros(3))


def _state(backend: MujocoBackend, names: list[str]) -> dict[str, np.ndarray]:
    """Every position, velocity and servo activation of the entities ``names``, one array each."""
    d = backend.data
    out = {}
    for name in names:
        e = backend._entities[name]
        acts = [d.act[j.servo.act] for j in e.joints.values()  # type: ignore[union-attr]
                if j.servo is not None and not j.servo.wheel]  # a person's joints have no servo
        out[name] = np.concatenate([d.qpos[e.qpos], d.qvel[e.dofs], np.array(acts)])
    return out


def _equal(a: dict[str, np.ndarray], b: dict[str, np.ndarray]) -> list[str]:
    """Names whose arrays differ in any bit."""
    return [n for n in a if not np.array_equal(a[n], b[n])]


@pytest.mark.parametrize("kind", ["box", "mesh", "urdf", "robot", "many"])
def test_others_keep_their_state_and_trajectory_bit_for_bit(kind: str) -> None:
    """Right after an add every other entity's state is bitwise what it was, and for 600 steps on it is bitwise
    that of a run without the add, the added entities moving (falling, landing) 1 m or more away."""
    world = _cleanup()
    new = _spawnable(world, kind)
    full = world.with_agents(world.agents + new)
    names = [e.name for e in world.entities]
    plain, spawned = MujocoBackend(), MujocoBackend()
    for backend in (plain, spawned):
        backend.build(world)
        _busy(backend)
        for _ in range(200):
            backend.step()
    before = _state(spawned, names)
    spawned.add_entities(full, [e.name for e in new])
    assert not _equal(before, _state(spawned, names))
    for step in range(STEPS):
        plain.step()
        spawned.step()
        differ = _equal(_state(plain, names), _state(spawned, names))
        assert not differ, f"step {step}: {differ} left the run without the add"
    for e in (e for e in new if not (isinstance(e, Object) and e.static)):
        assert abs(spawned.get_velocity(e.name)[0][2]) < 0.05  # landed (1.2 s) and at rest, not falling through
        assert spawned.get_pose(e.name)[0][2] > -0.01


def test_a_heavy_body_added_does_not_change_how_the_others_are_solved(make_world) -> None:
    """A 500 kg box added at rest far from four moving objects leaves their trajectory bitwise that of a run
    without it for 1,000 steps (its dofs are warm-started from their unconstrained acceleration, carry.py)."""
    world = make_world("""
      <object name="a" shape="box" size="0.2 0.2 0.2" pose="0 0 0.1"/>
      <object name="b" shape="sphere" size="0.1" pose="0.5 0 0.3"/>
      <object name="c" shape="box" size="0.1 0.1 0.1" pose="0 0 0.25"/>
      <object name="d" shape="cylinder" size="0.05 0.3" pose="1 0 0.15" mass="0.3"/>""")
    heavy = Object(name="heavy", shape="box", size=(1.0, 1.0, 1.0), mass=500.0, pose=Pose(xyz=(5.0, 5.0, 0.6)))
    plain, spawned = MujocoBackend(), MujocoBackend()
    for backend in (plain, spawned):
        backend.build(world)
        backend.set_velocity("a", np.array([1.0, 0.3, 0.0]))
        backend.set_velocity("d", np.array([0.0, 0.5, 0.0]), np.array([0.0, 0.0, 2.0]))
        for _ in range(50):
            backend.step()
    spawned.add_entities(world.with_agents(world.agents + (heavy,)), ["heavy"])
    names = ["a", "b", "c", "d"]
    for step in range(1000):
        plain.step()
        spawned.step()
        assert not _equal(_state(plain, names), _state(spawned, names)), f"step {step}"


def test_removing_keeps_the_others_state_bit_for_bit() -> None:
    """Removing a robot and an object leaves every other entity's positions, velocities and servo activations
    bitwise as they were, and the servos, held entities and forces go on as before the remove."""
    world = _cleanup()
    backend = MujocoBackend()
    backend.build(world)
    _busy(backend)
    backend.detach("robot_000", "l_hand_link", "can_0")
    for _ in range(100):
        backend.step()
    gone = {"robot_000", "wagon"}
    rest = [e.name for e in world.entities if e.name not in gone]
    before = _state(backend, rest)
    held = backend.get_pose("trashbox_2")
    backend.remove_entities(world.with_agents(tuple(a for a in world.agents if a.name not in gone)), sorted(gone))
    assert not _equal(before, _state(backend, rest))
    for _ in range(200):
        backend.step()
    assert np.array_equal(backend.get_pose("trashbox_2")[0], held[0])  # still held (dynamics off)
    assert backend.get_com("apple_2")[2] == pytest.approx(0.741, abs=0.01)  # still weightless, still on its table
    with pytest.raises(BackendError, match="no entity 'robot_000'"):
        backend.parts("robot_000")


def test_twenty_adds_and_removes_leave_no_element_behind() -> None:
    """After 20 rounds of adding a robot, a mesh and a box and removing them, the model has exactly the elements
    of a fresh build of the same world (bodies, joints, dofs, geoms, actuators, tendons, welds, excludes, meshes),
    so a step costs the same."""
    world = _cleanup()
    backend = MujocoBackend()
    backend.build(world)
    new = _spawnable(world, "many") + _spawnable(world, "mesh")
    full = world.with_agents(world.agents + new)
    for _ in range(20):
        backend.add_entities(full, [e.name for e in new])
        backend.step()
        backend.remove_entities(world, [e.name for e in new])
        backend.step()
    fresh = MujocoBackend()
    fresh.build(world)
    sizes = ("nbody", "njnt", "nv", "nq", "ngeom", "nu", "na", "ntendon", "neq", "nexclude", "nmesh", "nmat",
             "ntex", "nnames")
    assert {s: getattr(backend.model, s) for s in sizes} == {s: getattr(fresh.model, s) for s in sizes}
    assert len(backend._spec.frames) == len(fresh._spec.frames)


def test_reset_after_add_and_remove_restores_build_and_as_added_states() -> None:
    """After an add, run-time changes and a remove, reset puts every model value and the state of every entity
    to that of a fresh build of the resulting world (the old ones as built, the new ones as added)."""
    world = _cleanup()
    backend = MujocoBackend()
    backend.build(world)
    _busy(backend)
    for _ in range(50):
        backend.step()
    new = _spawnable(world, "many")
    full = world.with_agents(world.agents + new)
    backend.add_entities(full, [e.name for e in new])
    backend.set_mass("box_9", 4.0)
    backend.set_joint_target("robot_009", "l_elbow_joint", 0.5)
    for _ in range(50):
        backend.step()
    backend.detach("robot_000", "l_hand_link", "can_0")
    final = full.with_agents(tuple(a for a in full.agents if a.name != "wagon"))
    backend.remove_entities(final, ["wagon"])
    backend.reset()
    fresh = MujocoBackend()
    fresh.build(final)
    for field in ("body_pos", "body_quat", "body_mass", "body_inertia", "body_gravcomp", "geom_contype",
                  "geom_conaffinity", "actuator_forcerange", "tendon_frictionloss", "dof_invweight0", "qpos0"):
        assert np.array_equal(getattr(backend.model, field), getattr(fresh.model, field)), field
    for field in ("qpos", "qvel", "act", "ctrl", "eq_active"):
        assert np.array_equal(getattr(backend.data, field), getattr(fresh.data, field)), field


def test_a_rejected_entity_leaves_the_running_world_untouched(tmp_path: Path) -> None:
    """An entity MuJoCo rejects is a BackendError naming it; the running model, data and spec are untouched and
    a later add works."""
    bad = tmp_path / "bad.urdf"
    bad.write_text('<robot name="bad"><link name="a"><inertial><mass value="1"/><inertia ixx="1" ixy="0" ixz="0" '
                   'iyy="1" iyz="0" izz="1"/></inertial></link><link name="b"/><joint name="j" type="revolute">'
                   '<parent link="a"/><child link="b"/><axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" '
                   'velocity="1"/></joint></robot>')
    world = _cleanup()
    backend = MujocoBackend()
    backend.build(world)
    for _ in range(20):
        backend.step()
    model, data, qpos = backend.model, backend.data, backend.data.qpos.copy()
    spec_xml = backend._spec.to_xml()
    wrong = Robot(name="wrong_1", urdf=bad, pose=Pose(xyz=FAR))
    with pytest.raises(BackendError, match="robot 'wrong_1'"):
        backend.add_entities(world.with_agents(world.agents + (wrong,)), ["wrong_1"])
    assert backend.model is model and backend.data is data
    assert np.array_equal(backend.data.qpos, qpos)
    assert backend._spec.to_xml() == spec_xml
    box = _spawnable(world, "box")
    backend.add_entities(world.with_agents(world.agents + box), ["box_9"])
    assert backend.parts("box_9") == ["main"]


def test_contacts_keep_their_meaning_when_part_ids_are_renumbered() -> None:
    """Right after a remove renumbers the part ids, contacts() names the same touching (entity, part) pairs as
    before, minus those of the removed entity."""
    world = _cleanup()
    backend = MujocoBackend()
    backend.build(world)
    for _ in range(100):
        backend.step()

    def named() -> set[tuple[tuple[str, str], tuple[str, str]]]:
        return {(backend.part_of(a), backend.part_of(b)) for a, b in backend.contacts()}

    before = named()
    assert any(pair[0][0] == "robot_000" or pair[1][0] == "robot_000" for pair in before)
    backend.remove_entities(world.with_agents(tuple(a for a in world.agents if a.name != "robot_000")),
                            ["robot_000"])
    assert named() == {p for p in before if p[0][0] != "robot_000" and p[1][0] != "robot_000"}


def test_the_noslip_scale_stays_that_of_the_build() -> None:
    """The no-slip solver's tolerance scale (meaninertia x nv) after adding and removing equals the build's."""
    world = _cleanup()
    backend = MujocoBackend()
    backend.build(world)
    scale = backend.model.stat.meaninertia * backend.model.nv
    new = _spawnable(world, "many")
    backend.add_entities(world.with_agents(world.agents + new), [e.name for e in new])
    assert backend.model.nv > 50
    assert backend.model.stat.meaninertia * backend.model.nv == pytest.approx(scale, rel=1e-15)  # nearest double
    assert backend.model.opt.jacobian == mujoco.mjtJacobian.mjJAC_SPARSE
