"""PyBullet-specific behaviour of the bullet backend (the shared behaviour is in tests/backends)."""

from __future__ import annotations

import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pybullet as pb
import pytest
from sigcore_backend_bullet import BulletBackend

from sigcore import plugins
from sigcore.sim import Simulation
from sigcore.world import parse_world

ROOT = Path(__file__).parent.parent.parent
CLEANUP = ROOT / "worlds" / "cleanup.xml"


def test_registered_as_bullet() -> None:
    """The plugin registers BulletBackend under the name 'bullet'."""
    assert plugins.get_backend("bullet") is BulletBackend


def test_import_prints_no_banner() -> None:
    """Importing the plugin prints nothing (PyBullet's 'build time' banner on standard error is swallowed)."""
    r = subprocess.run([sys.executable, "-c", "import sigcore_backend_bullet"], capture_output=True, text=True)
    assert r.returncode == 0
    assert r.stdout == "" and r.stderr == ""


def test_one_client_per_instance() -> None:
    """Each backend has its own DIRECT client: stepping one does not move the other; close() disconnects."""
    world = parse_world(CLEANUP)
    a, b = BulletBackend(), BulletBackend()
    a.build(world)
    b.build(world)
    assert a.client != b.client
    a.set_pose("can_0", np.array([0.0, 0.0, 2.0]))
    for _ in range(100):
        a.step()
    assert a.get_pose("can_0")[0][2] < 2.0
    np.testing.assert_allclose(b.get_pose("can_0")[0], [-1.8, 1.75, 0.761], atol=1e-6)
    client = a.client
    a.close()
    assert not pb.isConnected(physicsClientId=client)
    assert pb.isConnected(physicsClientId=b.client)


def test_reset_after_filter_change_rebuilds_in_the_same_client() -> None:
    """A reset after a collision-mode change rebuilds the world in the same client (same id, same bodies)."""
    b = BulletBackend()
    b.build(parse_world(CLEANUP))
    client = b.client
    b.set_collision_mode("can_0", False)
    b.reset()
    assert b.client == client
    assert b.parts("robot_000")[0] == "base_link"
    b.step()
    assert b.get_pose("can_0")[0][2] == pytest.approx(0.761, abs=2e-3)  # collides again: still on the table


def test_cleanup_scan_matches_mujoco() -> None:
    """The clean-up world's first lidar scan on PyBullet equals MuJoCo's within 1 cm, beam for beam (a lidar
    inside its own housing sees out)."""
    world = parse_world(CLEANUP)
    scans = []
    for name in ("mujoco", "bullet"):
        sim = Simulation(world, name)
        sim.step(50)
        assert sim.entities.lidars[0].last is not None
        scans.append(sim.entities.lidars[0].last.ranges)
    assert np.isfinite(scans[1]).all()
    np.testing.assert_allclose(scans[1], scans[0], atol=0.01)


def test_cleanup_robot_stands_still_when_braked() -> None:
    """The clean-up robot, wheels braked, does not creep on its slippery casters once settled (0.5 s: it settles
    2 mm onto its contacts): < 1 mm and 1 mrad in the next 2 s."""
    b = BulletBackend()
    b.build(parse_world(CLEANUP))
    for _ in range(250):
        b.step()
    p0, q0 = b.get_pose("robot_000")
    for _ in range(1000):
        b.step()
    p1, q1 = b.get_pose("robot_000")
    assert np.linalg.norm(p1[:2] - p0[:2]) < 1e-3
    assert abs(2 * math.atan2(q1[3], q1[0]) - 2 * math.atan2(q0[3], q0[0])) < 1e-3


def test_static_human_is_frozen_then_freed_with_its_mass(tmp_path: Path) -> None:
    """A static human's base has mass 0 (PyBullet's fixed base: no work per step for it) and it keeps its world
    mass; with dynamics on after a set_mass it is a new rigid body with the doubled masses and falls onto its feet;
    after a reset (which then rebuilds the world) it is held again."""
    (tmp_path / "w.xml").write_text('<world name="w" timestep="0.002"><human name="h" pose="0 0 0.5"/></world>')
    b = BulletBackend()
    b.build(parse_world(tmp_path / "w.xml"))
    h = b._entities["h"]
    for _ in range(200):
        b.step()
    assert b._posed == {"h"} and pb.getDynamicsInfo(h.body, -1, physicsClientId=b.client)[0] == 0.0
    np.testing.assert_allclose(b.get_pose("h")[0], [0.0, 0.0, 0.5], atol=1e-12)
    mass0 = b.get_mass("h")
    assert mass0 == pytest.approx(70.0)
    b.set_mass("h", 2 * mass0)
    assert pb.getDynamicsInfo(h.body, -1, physicsClientId=b.client)[0] == 0.0  # still frozen
    b.set_dynamics_mode("h", True)
    h = b._entities["h"]
    assert h.rigid and b._posed == set()
    total = sum(pb.getDynamicsInfo(h.body, link, physicsClientId=b.client)[0] for link in h.links)
    assert total == pytest.approx(2 * mass0)
    for _ in range(300):
        b.step()
    assert b.get_pose("h")[0][2] == pytest.approx(0.0, abs=0.003)  # fell onto its feet
    b.reset()
    h = b._entities["h"]
    assert not h.rigid and pb.getDynamicsInfo(h.body, -1, physicsClientId=b.client)[0] == 0.0
    assert b.get_mass("h") == pytest.approx(mass0)
    for _ in range(100):
        b.step()
    np.testing.assert_allclose(b.get_pose("h")[0], [0.0, 0.0, 0.5], atol=1e-12)
