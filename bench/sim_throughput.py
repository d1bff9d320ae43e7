"""Real-time factor of a world through sigcore against raw ``mj_step`` on the same compiled model, same run.

Usage: .venv/bin/python bench/sim_throughput.py [WORLD] [--steps N] [--rounds R] [--smoke]
       --smoke: 1 round of 200 steps, to check that the bench runs and prints every figure (tests/bench).

Rounds alternate raw and sigcore so that machine noise hits both alike; ratios of medians are reported.
sigcore's steps include everything a headless run does: contact events (a collision listener is attached), lidar
scans at their rate, controller dispatch; the steps after which nothing is due are taken in MuJoCo's compiled loop
(``sigcore_backend_mujoco.steps``; ``SIGCORE_COMPILED_STEPS=0`` measures Python stepping). Three comparisons:

* sigcore (all on) against bare ``mj_step``: includes the lidar's ray casting, which bare ``mj_step`` does not do;
* sigcore (all on) against ``mj_step`` plus the same lidar done by hand (``mj_multiRay`` from the lidar link, same
  beams, same rate): the framework's overhead for the same work;
* sigcore with its lidars removed against bare ``mj_step``: the framework's overhead per step.

"Raw" includes putting the held entities (the standing person) back after each step, which a bare loop must do too:
left alone, a person's body falls in a heap.
"""

from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

import mujoco
import numpy as np
from sigcore_backend_mujoco import steps

from sigcore.agent import CollisionEvent
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
    ap.add_argument("--steps", type=int, default=5000, help="steps per round")
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--smoke", action="store_true", help="1 round of 200 steps: a check that the bench runs, not a "
                    "measurement")
    args = ap.parse_args()
    if args.smoke:
        args.rounds, args.steps = 1, 200

    world = parse_world(args.world)
    sim = Simulation(world, "mujoco")
    events: list[CollisionEvent] = []
    sim.events.subscribe("collision", events.append)  # contact events on, as with a transport attached
    model = sim.backend.model  # type: ignore[attr-defined]
    raw = mujoco.MjData(model)
    mujoco.mj_resetData(model, raw)
    raw.qpos[:] = sim.backend.data.qpos  # type: ignore[attr-defined]
    mujoco.mj_forward(model, raw)
    # the raw loop holds the kinematic person too (its coordinates put back after each step, as any simulator of a
    # kinematic body must): a person left to MuJoCo alone falls in a heap and costs more contacts than a held one
    held_q = np.array(sim.backend._held_qpos)  # type: ignore[attr-defined]
    held_v = np.array(sim.backend._held_values)  # type: ignore[attr-defined]
    held_d = np.array(sim.backend._held_dofs)  # type: ignore[attr-defined]

    def raw_step() -> None:
        mujoco.mj_step(model, raw)
        if held_q.size:
            raw.qpos[held_q] = held_v
            raw.qvel[held_d] = 0.0

    sim.step(200)  # warm up both
    for _ in range(200):
        raw_step()

    lidars = [(lidar, model.body(f"{lidar.robot}/{lidar.model.link}").id) for lidar in sim.entities.lidars]
    mask = np.zeros(6, dtype=np.uint8)
    mask[0] = 1

    def raw_lidar_steps(n: int, step0: int) -> None:
        for i in range(step0 + 1, step0 + n + 1):
            raw_step()
            for lidar, body in lidars:
                if i % lidar.period_steps == 0:
                    nray = lidar.model.beams
                    dirs = (lidar._local @ raw.xmat[body].reshape(3, 3).T).reshape(-1)
                    geomid = np.zeros(nray, dtype=np.int32)
                    dist = np.zeros(nray)
                    mujoco.mj_multiRay(model, raw, raw.xpos[body], dirs, mask, 1, body, geomid, dist, None, nray,
                                       lidar.model.range[1])

    rates: dict[str, list[float]] = {"raw": [], "raw+lidar": [], "sigcore": [], "sigcore-nolidar": []}
    quiet = Simulation(without_lidars(world), "mujoco")
    quiet.events.subscribe("collision", events.append)
    quiet.step(200)
    for r in range(args.rounds):
        t0 = time.perf_counter()
        for _ in range(args.steps):
            raw_step()
        rates["raw"].append(args.steps / (time.perf_counter() - t0))
        t0 = time.perf_counter()
        raw_lidar_steps(args.steps, r * args.steps)
        rates["raw+lidar"].append(args.steps / (time.perf_counter() - t0))
        t0 = time.perf_counter()
        sim.step(args.steps)
        rates["sigcore"].append(args.steps / (time.perf_counter() - t0))
        t0 = time.perf_counter()
        quiet.step(args.steps)
        rates["sigcore-nolidar"].append(args.steps / (time.perf_counter() - t0))

    dt = world.timestep
    med = {k: statistics.median(v) for k, v in rates.items()}
    print(f"world: {args.world}  timestep: {dt} s  bodies: {model.nbody}  geoms: {model.ngeom}  "
          f"lidars: {', '.join(f'{x.model.beams} beams at {x.model.rate} Hz' for x in sim.entities.lidars) or 'none'}")
    print(f"rounds: {args.rounds} x {args.steps} steps each, alternating")
    print(f"sigcore: {steps.status()}")
    for k, label in (("raw", "raw mj_step"), ("raw+lidar", "raw mj_step + mj_multiRay lidar"),
                     ("sigcore", "sigcore step (all on)"), ("sigcore-nolidar", "sigcore step, no lidar")):
        print(f"  {label:34s} {med[k]:9.0f} steps/s  {1e6 / med[k]:6.1f} us/step  real-time factor {med[k] * dt:6.1f}")
    print(f"ratio sigcore / (raw + same lidar):     {med['sigcore'] / med['raw+lidar']:.3f}  (target >= 0.93)")
    print(f"ratio sigcore without lidar / raw:      {med['sigcore-nolidar'] / med['raw']:.3f}  (target >= 0.9)")
    print(f"ratio sigcore (all on) / bare mj_step:  {med['sigcore'] / med['raw']:.3f}  (includes the lidar's rays)")


if __name__ == "__main__":
    main()
