"""How much a busy neighbour on the other CPU slows the simulation on this one (a control for viewer_overhead.py).

Usage: .venv/bin/python bench/other_core_load.py [--rounds R] [--steps N] [--smoke]
       --smoke: 1 round of 100 steps, to check that the bench runs and prints every figure (tests/bench).

This process (the simulation) is pinned to CPU 0. Three simulations of worlds/cleanup.xml with the scripted robot
advance in turn, N steps a round, R rounds: ``quiet`` (CPU 1 idle), ``memory`` (a process on CPU 1 sorting and
copying 32 MB arrays: heavy memory traffic, like software WebGL in a browser) and ``compute`` (a process on CPU 1
counting in a Python loop: compute only). It prints the median steps per second of each and the ratio to quiet. A
ratio well below 1 for ``memory`` means that on this machine a browser rendering on the other CPU slows the
simulation through the shared caches and memory, whatever the viewer does.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

from sigcore.sim import Simulation
from sigcore.world import parse_world

ROOT = Path(__file__).resolve().parent.parent
LOADS = {"memory": "import numpy as np\nwhile True:\n    a = np.random.rand(4_000_000); a.sort(); b = a.copy()",
         "compute": "x = 0\nwhile True:\n    x += 1"}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rounds", type=int, default=8)
    ap.add_argument("--steps", type=int, default=2500)
    ap.add_argument("--smoke", action="store_true", help="1 round of 100 steps: a check that the bench runs, not a "
                    "measurement")
    args = ap.parse_args()
    if args.smoke:
        args.rounds, args.steps = 1, 100
    os.sched_setaffinity(0, {0})
    world = parse_world(ROOT / "worlds" / "cleanup.xml")
    sims = {k: Simulation(world, "mujoco", controllers={"robot_000": "cleanup.robot"})
            for k in ("quiet", *LOADS)}
    rates: dict[str, list[float]] = {k: [] for k in sims}
    for r in range(args.rounds):
        for name, sim in sims.items():
            load = None
            if name in LOADS:
                load = subprocess.Popen([sys.executable, "-c", LOADS[name]])
                os.sched_setaffinity(load.pid, {1})
                time.sleep(0.5)  # running
            try:
                t = time.perf_counter()
                sim.step(args.steps)
                rates[name].append(args.steps / (time.perf_counter() - t))
            finally:
                if load is not None:
                    load.kill()
                    load.wait()
        print(f"  round {r + 1}: " + ", ".join(f"{k} {v[-1]:6.0f}" for k, v in rates.items()), flush=True)
    quiet = statistics.median(rates["quiet"])
    print(f"simulation on CPU 0, {args.rounds} rounds x {args.steps} steps, medians:")
    for name, values in rates.items():
        print(f"  {name:8s} {statistics.median(values):7.0f} steps/s  ratio to quiet "
              f"{statistics.median(values) / quiet:.3f}")


if __name__ == "__main__":
    main()
