"""Spawning and deleting while running: latency against a full build, and throughput afterwards (issue 12).

Usage: .venv/bin/python bench/spawn.py [--backends mujoco bullet] [--repeats 5] [--steps 2000] [--smoke]
       --smoke: 1 repeat of 100 steps, to check that the bench runs and prints every figure (tests/bench).

Per backend, on worlds/cleanup.xml:

* build: parsing the world file and building the simulation from scratch (``Simulation(parse_world(...))``);
* spawn 1: ``sim.spawn`` of one box (a world-format element) while running;
* spawn 10: ``sim.spawn`` of ten boxes in one call (``spawn_entities``: one recompile on MuJoCo);
* delete 1: ``sim.delete`` of one spawned box;
* throughput: steps per second of the world after 20 spawns and 10 deletes (10 spawned boxes left, resting on the
  floor) against a fresh world that has the same 10 boxes in its file at the same poses, measured alternately in
  the same process; the target is a ratio >= 0.95 (no leftovers of deleted bodies slow the step).

MuJoCo only: the cost of the sparse Jacobian that keeps other bodies bitwise when entities come and go (see
docs/backends.md): a clean-up step with ``mjJAC_SPARSE`` against MuJoCo's automatic choice (dense below 60 dofs),
switched on the same model in alternation.

Medians over ``--repeats``; the machine is shared and noisy, so compare the ratios.
"""

from __future__ import annotations

import argparse
import logging
import statistics
import time
from pathlib import Path

from sigcore.sim import Simulation
from sigcore.world import parse_world
from sigcore.world.resources import SpawnRequest

ROOT = Path(__file__).resolve().parent.parent
CLEANUP = ROOT / "worlds" / "cleanup.xml"
BOX = '<object shape="box" size="0.1 0.1 0.1" mass="0.2"/>'


def _spot(i: int) -> tuple[float, float, float]:
    """A free place on the clean-up room's floor for box ``i`` (a grid in the open middle of the room)."""
    return (-3.0 + 0.5 * (i % 10), -0.8 + 0.5 * (i // 10), 0.05)


def _median_time(fn, repeats: int) -> float:  # type: ignore[no-untyped-def]
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def _steps_per_second(sim: Simulation, steps: int) -> float:
    start = time.perf_counter()
    sim.step(steps)
    return steps / (time.perf_counter() - start)


def figures(backend: str, repeats: int, steps: int) -> dict[str, float]:
    out: dict[str, float] = {}
    out["build_ms"] = 1000 * _median_time(lambda: Simulation(parse_world(CLEANUP), backend=backend), repeats)

    one, ten, gone = [], [], []
    for r in range(repeats):
        sim = Simulation(parse_world(CLEANUP), backend=backend)
        sim.step(10)
        start = time.perf_counter()
        [name] = sim.entities.spawn([SpawnRequest(name=f"one_{r}", resource=BOX, xyz=_spot(0))])
        one.append(time.perf_counter() - start)
        assert isinstance(name, str), name
        start = time.perf_counter()
        names = sim.entities.spawn([SpawnRequest(name=f"b{i}", resource=BOX, xyz=_spot(i + 1)) for i in range(10)])
        ten.append(time.perf_counter() - start)
        assert all(isinstance(n, str) for n in names), names
        start = time.perf_counter()
        sim.entities.delete([name])
        gone.append(time.perf_counter() - start)
    out["spawn1_ms"] = 1000 * statistics.median(one)
    out["spawn10_ms"] = 1000 * statistics.median(ten)
    out["delete1_ms"] = 1000 * statistics.median(gone)

    # throughput: 20 spawns (one at a time) and 10 deletes, against a fresh world with the 10 boxes left
    churned = Simulation(parse_world(CLEANUP), backend=backend)
    churned.step(10)
    for i in range(20):
        result = churned.entities.spawn([SpawnRequest(name=f"c{i}", resource=BOX, xyz=_spot(i))])
        assert isinstance(result[0], str), result
        churned.step(5)
    churned.entities.delete([f"c{i}" for i in range(0, 20, 2)])
    kept = [f"c{i}" for i in range(1, 20, 2)]
    text = CLEANUP.read_text()
    boxes = "".join(f'<object name="{n}" shape="box" size="0.1 0.1 0.1" mass="0.2" '
                    f'pose="{" ".join(repr(v) for v in _spot(int(n[1:])))}"/>\n' for n in kept)
    fresh = Simulation(parse_world(CLEANUP, text.replace("</world>", boxes + "</world>")), backend=backend)
    fresh.step(10)
    churned.step(500)  # both settle
    fresh.step(500)
    ratios, rates_c, rates_f = [], [], []
    for _ in range(repeats):
        c = _steps_per_second(churned, steps)
        f = _steps_per_second(fresh, steps)
        rates_c.append(c)
        rates_f.append(f)
        ratios.append(c / f)
    out["churned_steps_per_s"] = statistics.median(rates_c)
    out["fresh_steps_per_s"] = statistics.median(rates_f)
    out["throughput_ratio"] = statistics.median(ratios)
    return out


def sparse_cost(repeats: int, steps: int) -> tuple[float, float]:
    """Microseconds per clean-up step with the sparse Jacobian and with MuJoCo's automatic choice."""
    import mujoco

    sim = Simulation(parse_world(CLEANUP), backend="mujoco")
    model = sim.backend.model  # type: ignore[attr-defined]
    sim.step(500)
    times: dict[str, list[float]] = {"sparse": [], "auto": []}
    for _ in range(repeats):
        for mode, value in (("sparse", mujoco.mjtJacobian.mjJAC_SPARSE), ("auto", mujoco.mjtJacobian.mjJAC_AUTO)):
            model.opt.jacobian = value
            start = time.perf_counter()
            sim.step(steps)
            times[mode].append(1e6 * (time.perf_counter() - start) / steps)
    return statistics.median(times["sparse"]), statistics.median(times["auto"])


def arguments(doc: str) -> argparse.Namespace:
    """``--backends``, ``--repeats``, ``--steps`` and ``--smoke`` of the run-time change benches (this one and
    worlds.py); ``--smoke`` sets 1 repeat of 100 steps."""
    parser = argparse.ArgumentParser(description=doc.splitlines()[0])
    parser.add_argument("--backends", nargs="+", default=["mujoco", "bullet"])
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--steps", type=int, default=2000)
    parser.add_argument("--smoke", action="store_true", help="1 repeat of 100 steps: a check that the bench runs, "
                        "not a measurement")
    args = parser.parse_args()
    if args.smoke:
        args.repeats, args.steps = 1, 100
    return args


def main() -> None:
    args = arguments(__doc__)
    logging.getLogger("sigcore").setLevel(logging.WARNING)
    print(f"{'backend':8} {'build ms':>9} {'spawn1 ms':>9} {'spawn10 ms':>10} {'delete1 ms':>10} "
          f"{'churned st/s':>12} {'fresh st/s':>10} {'ratio':>6}")
    for backend in args.backends:
        f = figures(backend, args.repeats, args.steps)
        print(f"{backend:8} {f['build_ms']:9.1f} {f['spawn1_ms']:9.1f} {f['spawn10_ms']:10.1f} {f['delete1_ms']:10.1f} "
              f"{f['churned_steps_per_s']:12.0f} {f['fresh_steps_per_s']:10.0f} {f['throughput_ratio']:6.3f}")
    if "mujoco" in args.backends:
        sparse, auto = sparse_cost(args.repeats, args.steps)
        print(f"mujoco clean-up step: sparse Jacobian {sparse:.1f} us, automatic {auto:.1f} us, "
              f"ratio {sparse / auto:.3f}")


if __name__ == "__main__":
    main()
