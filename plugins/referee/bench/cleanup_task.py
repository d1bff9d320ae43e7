"""Time the whole clean-up task done by the scripted robot (controller ``cleanup.robot``) on MuJoCo.

Usage: .venv/bin/python plugins/referee/bench/cleanup_task.py [WORLD] [--runs N]

Loads WORLD (default worlds/cleanup.xml, which enables the referee), attaches ``CleanupRobot`` to robot_000, runs
until the referee ends the task, and prints the simulated time, the wall time (median of N runs), the real-time
factor and the referee's score table of the last run.
"""

from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

from sigcore_referee import CleanupRobot, Referee

from sigcore.sim import Simulation
from sigcore.world import parse_world

ROOT = Path(__file__).resolve().parents[3]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("world", nargs="?", default=str(ROOT / "worlds" / "cleanup.xml"))
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--limit", type=float, default=300.0, help="give up after this many simulated seconds")
    args = ap.parse_args()
    walls, sims, build = [], [], []
    referee: Referee | None = None
    for _ in range(args.runs):
        t0 = time.perf_counter()
        sim = Simulation(parse_world(Path(args.world)), "mujoco")
        sim.entities.set_controller("robot_000", CleanupRobot())
        feature = sim.features["referee"]
        assert isinstance(feature, Referee)
        referee = feature
        t1 = time.perf_counter()
        while not referee.finished and sim.time < args.limit:
            sim.step(100)
        walls.append(time.perf_counter() - t1)
        sims.append(feature.end_time if feature.end_time is not None else sim.time)
        build.append(t1 - t0)
    assert referee is not None
    wall = statistics.median(walls)
    print(f"world: {args.world}; {args.runs} runs")
    print(f"  task simulated time: {statistics.median(sims):7.2f} s  (runs: {', '.join(f'{s:.2f}' for s in sims)})")
    print(f"  task wall time:      {wall:7.2f} s  (runs: {', '.join(f'{w:.2f}' for w in walls)}); "
          f"build {statistics.median(build):.2f} s")
    print(f"  real-time factor:    {statistics.median(sims) / wall:7.1f}")
    for line in referee.report():
        print(line)


if __name__ == "__main__":
    main()
