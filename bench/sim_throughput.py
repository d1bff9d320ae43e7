"""Real-time factor of a world through sigcore against raw ``mj_step`` on the same compiled model, same run.

Usage: .venv/bin/python bench/sim_throughput.py [WORLD] [--steps N] [--rounds R]

Rounds alternate raw and sigcore so that machine noise hits both alike; the ratio of medians is reported.
sigcore's steps include everything a headless run does: contact events (a collision listener is attached), lidar
scans at their rate, controller dispatch.
"""

from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

import mujoco

from sigcore.sim import Simulation
from sigcore.world import parse_world

ROOT = Path(__file__).resolve().parent.parent


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("world", nargs="?", default=str(ROOT / "worlds" / "cleanup.xml"))
    ap.add_argument("--steps", type=int, default=5000, help="steps per round")
    ap.add_argument("--rounds", type=int, default=5)
    args = ap.parse_args()

    world = parse_world(args.world)
    sim = Simulation(world, "mujoco")
    events = []
    sim.collision_observers.append(events.append)  # contact events on, as with a transport attached
    model = sim.backend.model  # type: ignore[attr-defined]
    raw = mujoco.MjData(model)
    mujoco.mj_resetData(model, raw)
    raw.qpos[:] = sim.backend.data.qpos  # type: ignore[attr-defined]
    mujoco.mj_forward(model, raw)
    sim.step(200)  # warm up both
    for _ in range(200):
        mujoco.mj_step(model, raw)

    raw_rates, core_rates = [], []
    for _ in range(args.rounds):
        t0 = time.perf_counter()
        for _ in range(args.steps):
            mujoco.mj_step(model, raw)
        raw_rates.append(args.steps / (time.perf_counter() - t0))
        t0 = time.perf_counter()
        sim.step(args.steps)
        core_rates.append(args.steps / (time.perf_counter() - t0))

    dt = world.timestep
    raw_med, core_med = statistics.median(raw_rates), statistics.median(core_rates)
    print(f"world: {args.world}  timestep: {dt} s  bodies: {model.nbody}  geoms: {model.ngeom}  "
          f"lidars: {len(sim.lidars)}")
    print(f"rounds: {args.rounds} x {args.steps} steps, alternating")
    print(f"raw mj_step:   {raw_med:10.0f} steps/s   real-time factor {raw_med * dt:7.1f}")
    print(f"sigcore step:  {core_med:10.0f} steps/s   real-time factor {core_med * dt:7.1f}")
    print(f"ratio sigcore/raw: {core_med / raw_med:.3f}  (target >= 0.9)")
    print(f"per step: raw {1e6 / raw_med:.1f} us, sigcore {1e6 / core_med:.1f} us, "
          f"overhead {1e6 / core_med - 1e6 / raw_med:.1f} us")


if __name__ == "__main__":
    main()
