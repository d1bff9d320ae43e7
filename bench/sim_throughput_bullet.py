"""Real-time factor of a world through sigcore on PyBullet against raw ``stepSimulation`` on the same scene, same run.

Usage: .venv/bin/python bench/sim_throughput_bullet.py [WORLD] [--steps N] [--rounds R] [--smoke]
       --smoke: 1 round of 100 steps, to check that the bench runs and prints every figure (tests/bench).

The raw scene is the same world built by the same backend into a second PyBullet client (same bodies, wheel motors
and engine parameters; arm joints held by plain ``POSITION_CONTROL`` motors at full force, as raw PyBullet code
would), then stepped with bare ``pybullet.stepSimulation``. Rounds alternate raw and sigcore so that
machine noise hits both alike; ratios of medians are reported. sigcore's steps include everything a headless run
does: contact events (a collision listener is attached), lidar scans at their rate, controller dispatch. As in
``bench/sim_throughput.py`` (MuJoCo), three comparisons:

* sigcore (all on) against bare ``stepSimulation``: includes the lidar's ray casting;
* sigcore (all on) against ``stepSimulation`` plus the same lidar done by hand (``rayTestBatch`` from the lidar
  link, same beams, same rate, no exclusion of the robot): the framework's overhead for the same work;
* sigcore with its lidars removed against bare ``stepSimulation``: the framework's overhead per step;
* the same without the world's feature plugins' step subscribers (referee, IK, ...): what the core and the backend
  cost (arm servos with the world's gains, contact events, the held human).
"""

from __future__ import annotations

import argparse
import statistics
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
from sigcore_backend_bullet import BulletBackend

from sigcore.agent import CollisionEvent
from sigcore.geometry import quat_to_matrix
from sigcore.sim import Simulation
from sigcore.world import parse_world
from sigcore.world.models import Robot, World

ROOT = Path(__file__).resolve().parent.parent


def without_lidars(world: World) -> World:
    """``world`` with no ``<lidar>`` on any robot (the framework's cost per step without sensors)."""
    return world.with_agents(tuple(a.model_copy(update={"lidars": ()}) if isinstance(a, Robot) else a
                                   for a in world.agents))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("world", nargs="?", default=str(ROOT / "worlds" / "cleanup.xml"))
    ap.add_argument("--steps", type=int, default=2000, help="steps per round")
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--smoke", action="store_true", help="1 round of 100 steps: a check that the bench runs, not a "
                    "measurement")
    args = ap.parse_args()
    if args.smoke:
        args.rounds, args.steps = 1, 100

    import pybullet as pb

    world = parse_world(args.world)
    sim = Simulation(world, "bullet")
    events: list[CollisionEvent] = []
    sim.events.subscribe("collision", events.append)  # contact events on, as with a transport attached
    raw_backend = BulletBackend()
    raw_backend.build(world)
    raw = raw_backend.client
    for e in raw_backend._entities.values():  # what a raw PyBullet user would write: fixed-force arm servos
        for j in e.joints.values():
            if not j.wheel:
                pb.setJointMotorControl2(e.body, j.index, pb.POSITION_CONTROL, targetPosition=j.initial,
                                         force=j.max_torque, physicsClientId=raw)
    sim.step(200)  # warm up both
    for _ in range(200):
        pb.stepSimulation(physicsClientId=raw)

    def raw_lidar_steps(n: int, step0: int) -> None:
        for i in range(step0 + 1, step0 + n + 1):
            pb.stepSimulation(physicsClientId=raw)
            for lidar in sim.entities.lidars:
                if i % lidar.period_steps == 0:
                    pos, quat = raw_backend.get_pose(lidar.robot, lidar.model.link)
                    dirs = lidar._local @ quat_to_matrix(quat).T
                    ends = pos + dirs * lidar.model.range[1]
                    hits = pb.rayTestBatch([pos.tolist()] * len(dirs), ends.tolist(), physicsClientId=raw)
                    np.array([h[2] for h in hits]) * lidar.model.range[1]

    rates: dict[str, list[float]] = {"raw": [], "raw+lidar": [], "sigcore": [], "sigcore-nolidar": [],
                                     "sigcore-core": []}
    quiet = Simulation(without_lidars(world), "bullet")
    quiet.events.subscribe("collision", events.append)
    quiet.step(200)
    step_subscriptions = quiet.events.subscriptions("step")
    cpu: dict[str, list[float]] = {k: [] for k in rates}

    def timed(key: str, run: Callable[[], None]) -> None:
        t0, c0 = time.perf_counter(), time.thread_time()
        run()
        rates[key].append(args.steps / (time.perf_counter() - t0))
        cpu[key].append(args.steps / (time.thread_time() - c0))

    def raw_steps() -> None:
        for _ in range(args.steps):
            pb.stepSimulation(physicsClientId=raw)

    for r in range(args.rounds):
        timed("raw", raw_steps)
        timed("raw+lidar", lambda: raw_lidar_steps(args.steps, r * args.steps))  # noqa: B023 (called at once)
        timed("sigcore", lambda: sim.step(args.steps))
        timed("sigcore-nolidar", lambda: quiet.step(args.steps))
        for subscription in step_subscriptions:
            subscription.cancel()
        timed("sigcore-core", lambda: quiet.step(args.steps))
        step_subscriptions = tuple(quiet.events.subscribe("step", s.fn, s.owner) for s in step_subscriptions)

    dt = world.timestep
    med = {k: statistics.median(v) for k, v in rates.items()}
    print(f"world: {args.world}  timestep: {dt} s  bodies: {pb.getNumBodies(physicsClientId=raw)}  "
          f"lidars: {', '.join(f'{x.model.beams} beams at {x.model.rate} Hz' for x in sim.entities.lidars) or 'none'}")
    print(f"pybullet {pb.getAPIVersion()}; rounds: {args.rounds} x {args.steps} steps each, alternating")
    for k, label in (("raw", "raw stepSimulation"), ("raw+lidar", "raw stepSimulation + rayTestBatch lidar"),
                     ("sigcore", "sigcore step (all on)"), ("sigcore-nolidar", "sigcore step, no lidar"),
                     ("sigcore-core", "sigcore step, no lidar, no features")):
        print(f"  {label:40s} {med[k]:9.0f} steps/s  {1e6 / med[k]:7.1f} us/step  real-time factor "
              f"{med[k] * dt:6.1f}")
    cmed = {k: statistics.median(v) for k, v in cpu.items()}
    print("ratios (wall clock; CPU time of this thread in brackets, which leaves out time the process waited for a "
          "core):")
    for label, a, b, note in (
            ("sigcore / (raw + same lidar)", "sigcore", "raw+lidar", "target >= 0.9"),
            ("sigcore without lidar / raw", "sigcore-nolidar", "raw", "target >= 0.9"),
            ("sigcore (all on) / bare stepSimulation", "sigcore", "raw", "includes the lidar's rays"),
            ("sigcore without lidar, features / raw", "sigcore-core", "raw", "core + backend")):
        print(f"  {label + ':':42s} {med[a] / med[b]:.3f}  ({cmed[a] / cmed[b]:.3f})  {note}")

if __name__ == "__main__":
    main()
