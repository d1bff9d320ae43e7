"""Replacing the running world (issue 12, item 4): ``load_world`` against building the world from scratch.

Usage: .venv/bin/python bench/worlds.py [--backends mujoco bullet] [--repeats 5] [--steps 2000] [--smoke]
       --smoke: 1 repeat of 100 steps, to check that the bench runs and prints every figure (tests/bench).

Per backend:

* build: parsing worlds/cleanup.xml and building a new simulation of it (``Simulation(parse_world(...))``), what a
  user without ``load_world`` would do (plus a new process and ROS node);
* load: ``sim.load_world`` of the parsed clean-up world into a running simulation of worlds/arm6.xml (the old
  world torn down, the new one built; the world is parsed outside the timing, as the build's parse is inside it);
* parse: the parse alone, so that the two compare;
* throughput: steps per second of the clean-up world after 20 loads (arm6 and cleanup in turn) against a fresh
  simulation of it, measured alternately in the same process: nothing of the unloaded worlds may slow the step
  (target: ratio >= 0.95).

Medians over ``--repeats``; the machine is shared and noisy, so compare the ratios.
"""

from __future__ import annotations

import logging
import statistics
import time
from pathlib import Path

from spawn import arguments  # bench/spawn.py: run as a script, bench/ is on the path

from sigcore.sim import Simulation
from sigcore.world import parse_world

ROOT = Path(__file__).resolve().parent.parent
CLEANUP = ROOT / "worlds" / "cleanup.xml"
ARM6 = ROOT / "worlds" / "arm6.xml"


def _timed(fn) -> float:  # type: ignore[no-untyped-def]
    start = time.perf_counter()
    fn()
    return time.perf_counter() - start


def _steps_per_second(sim: Simulation, steps: int) -> float:
    sim.control.play()
    start = time.perf_counter()
    sim.step(steps)
    return steps / (time.perf_counter() - start)


def figures(backend: str, repeats: int, steps: int) -> dict[str, float]:
    cleanup, arm6 = parse_world(CLEANUP), parse_world(ARM6)
    build = statistics.median(_timed(lambda: Simulation(parse_world(CLEANUP), backend)) for _ in range(repeats))
    parse = statistics.median(_timed(lambda: parse_world(CLEANUP)) for _ in range(repeats))
    loads = []
    for _ in range(repeats):
        sim = Simulation(arm6, backend)
        sim.step(10)
        loads.append(_timed(lambda sim=sim: sim.worlds.load(cleanup)))
    reused = Simulation(cleanup, backend)
    for i in range(20):
        reused.worlds.load(arm6 if i % 2 == 0 else cleanup)
    assert reused.world is cleanup
    fresh = Simulation(cleanup, backend)
    a, b = [], []
    for _ in range(repeats):
        a.append(_steps_per_second(reused, steps))
        b.append(_steps_per_second(fresh, steps))
    return {"build_ms": 1e3 * build, "parse_ms": 1e3 * parse, "load_ms": 1e3 * statistics.median(loads),
            "after_20_loads": statistics.median(a), "fresh": statistics.median(b),
            "ratio": statistics.median(a) / statistics.median(b)}


def main() -> None:
    args = arguments(__doc__)
    logging.basicConfig(level=logging.WARNING)
    print("| backend | build clean-up from scratch (parse + Simulation) | parse alone | load_world of it while "
          "running | steps/s after 20 loads | fresh | ratio |")
    print("|---|---|---|---|---|---|---|")
    for backend in args.backends:
        f = figures(backend, args.repeats, args.steps)
        print(f"| {backend} | {f['build_ms']:.1f} ms | {f['parse_ms']:.1f} ms | {f['load_ms']:.1f} ms | "
              f"{f['after_20_loads']:.0f} | {f['fresh']:.0f} | {f['ratio']:.3f} |", flush=True)


if __name__ == "__main__":
    main()
