"""Time MujocoBackend.step() against raw mujoco.mj_step on the same compiled model.

Usage: ``python plugins/backend_mujoco/bench/step_overhead.py [WORLD.xml]`` (default: ``worlds/cleanup.xml``).
Prints microseconds per step (best of several interleaved blocks) for: the raw step, the backend's step with
the world as built (a static human is held), with nothing held, and the cost of reading one pose and contacts
per step.
"""

from __future__ import annotations

import copy
import sys
import time
from collections.abc import Callable
from pathlib import Path

import mujoco
from sigcore_backend_mujoco import MujocoBackend

from sigcore.world import Human, parse_world

BLOCK = 2000
ROUNDS = 7


def _best(fn: Callable[[], None]) -> float:
    best = float("inf")
    for _ in range(ROUNDS):
        start = time.perf_counter()
        for _ in range(BLOCK):
            fn()
        best = min(best, (time.perf_counter() - start) / BLOCK)
    return best * 1e6


def main() -> None:
    """Build the world, warm up, and print the figures."""
    path = Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).parents[3] / "worlds" / "cleanup.xml"
    world = parse_world(path)
    start = time.perf_counter()
    backend = MujocoBackend()
    backend.build(world)
    built = time.perf_counter() - start
    for _ in range(500):
        backend.step()
    model, data = copy.copy(backend.model), copy.copy(backend.data)
    raw = _best(lambda: mujoco.mj_step(model, data))
    as_built = _best(backend.step)
    for human in (a for a in world.agents if isinstance(a, Human)):
        backend.set_dynamics_mode(human.name, True)
    free = _best(backend.step)
    raw_again = _best(lambda: mujoco.mj_step(model, data))
    robot = next(iter(backend._entities))

    def step_and_read() -> None:
        backend.step()
        backend.get_pose(robot)
        backend.contacts()

    read = _best(step_and_read)
    raw = min(raw, raw_again)
    print(f"world {path.name}: nbody {model.nbody}, nv {model.nv}, ngeom {model.ngeom}; "
          f"built in {built * 1e3:.1f} ms")
    print(f"raw mj_step                    {raw:7.2f} us")
    print(f"backend.step (as built)        {as_built:7.2f} us  ratio {as_built / raw:.3f}")
    print(f"backend.step (nothing held)    {free:7.2f} us  ratio {free / raw:.3f}")
    print(f"step + get_pose + contacts     {read:7.2f} us  ratio {read / raw:.3f}")


if __name__ == "__main__":
    main()
