"""Where a sigcore step's time goes, measured in place: the step loop rebuilt from its parts, one more part a variant.

Usage: .venv/bin/python bench/step_breakdown.py [WORLD] [--steps N] [--rounds R] [--smoke]
       --smoke: 2 rounds of 100 steps, to check that the bench runs and prints every figure (tests/bench).

``bench/sim_throughput.py`` says how much slower a sigcore step is than ``mj_step``; this says which part of the
step costs what. Each variant runs N steps of the same simulation (WORLD, default worlds/cleanup.xml, with a
collision listener, as with a transport attached), each one part more than the one before:

* ``mj_step``: MuJoCo's step alone, on a second ``MjData`` of the same model (the raw engine);
* ``backend``: ``backend.step()`` (``mj_step``, the counters, the held entities' restore);
* ``+ contacts``: and the contact events (``sim.entities.contacts.events``);
* ``+ step channel``: and the ``step`` channel's subscribers (the referee, IK; the referee's look every 50 steps
  is not in it: the loop holds ``sim.step_count`` at an odd number);
* ``+ lidar``: and the lidar scans at their rate (``lidar.scan`` and the ``scan`` channel);
* ``Simulation.step``: the whole step as a run does it.

The variants alternate round by round; the figures are medians of the simulation thread's CPU time per step
(``time.thread_time``: another process's time is not counted, its effect on the caches is). The marginal cost of
a part is its variant minus the one before. Beside them, each part's cost on its own (``timeit``, warm caches):
the difference is what the Python work costs ``mj_step`` in caches.
"""

from __future__ import annotations

import argparse
import statistics
import time
import timeit
from collections.abc import Callable
from pathlib import Path

import mujoco

from sigcore.agent import CollisionEvent
from sigcore.backend import Backend
from sigcore.sim import Simulation
from sigcore.sim.lidar import LidarSensor
from sigcore.world import parse_world

ROOT = Path(__file__).resolve().parent.parent


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("world", nargs="?", default=str(ROOT / "worlds" / "cleanup.xml"))
    ap.add_argument("--steps", type=int, default=3000, help="steps per variant and round")
    ap.add_argument("--rounds", type=int, default=15)
    ap.add_argument("--smoke", action="store_true", help="2 rounds of 100 steps: a check that the bench runs, not a "
                    "measurement")
    args = ap.parse_args()
    if args.smoke:
        args.rounds, args.steps = 2, 100

    sim = Simulation(parse_world(args.world), "mujoco")
    events: list[CollisionEvent] = []
    sim.events.subscribe("collision", events.append)
    sim.step(201)  # odd: a feature that looks every k (even) steps does not look in the partial loops (they hold it)
    backend, hub = sim.backend, sim.events
    contacts, lidars = sim.entities.contacts, sim.entities.lidars
    model = backend.model  # type: ignore[attr-defined]
    raw = mujoco.MjData(model)
    raw.qpos[:] = backend.data.qpos  # type: ignore[attr-defined]
    mujoco.mj_forward(model, raw)
    n = args.steps
    count = [sim.step_count * 7 + 1]  # the contact tracker's step numbers: new ones each call, never sim's own

    def raw_steps() -> None:
        for _ in range(n):
            mujoco.mj_step(model, raw)

    def partial(contacts_on: bool, channel_on: bool, lidar_on: bool) -> Callable[[], None]:
        def steps() -> None:
            k = count[0]
            for _ in range(n):
                backend.step()
                k += 1
                if contacts_on:
                    for _triple in contacts.events(k):
                        pass
                if lidar_on:
                    for lidar in lidars:
                        if k % lidar.period_steps == 0:
                            hub.emit("scan", lidar.scan(backend, 0.0))
                if channel_on:
                    hub.emit("step", sim)
            count[0] = k
        return steps

    variants: dict[str, Callable[[], None]] = {
        "mj_step": raw_steps,
        "backend": partial(False, False, False),
        "+ contacts": partial(True, False, False),
        "+ step channel": partial(True, True, False),
        "+ lidar": partial(True, True, True),
        "Simulation.step": lambda: sim.step(n if n % 2 == 0 else n + 1),  # sim.step_count stays odd
    }
    cpu: dict[str, list[float]] = {name: [] for name in variants}
    for r in range(args.rounds):
        order = list(variants) if r % 2 == 0 else list(reversed(variants))
        for name in order:
            t0 = time.thread_time()
            variants[name]()
            cpu[name].append((time.thread_time() - t0) / n * 1e6)
    med = {name: statistics.median(v) for name, v in cpu.items()}

    # each part alone, warm (timeit): a step's contacts, a step-channel delivery, a scan every period
    sim_count = sim.step_count
    alone_contacts = _alone(lambda: (backend.step(), contacts.events(_next(count)))) - _alone(backend.step)
    alone_channel = _alone(lambda: hub.emit("step", sim))
    alone_lidar = 0.0
    for lidar in lidars:
        alone_lidar += _alone(partial_scan(lidar, backend)) / lidar.period_steps
    alone = {"backend": _alone(backend.step) - _alone(lambda: mujoco.mj_step(model, raw)),
             "+ contacts": alone_contacts, "+ step channel": alone_channel, "+ lidar": alone_lidar}
    assert sim.step_count == sim_count

    print(f"world: {args.world}  {args.rounds} rounds x {args.steps} steps per variant, alternating; "
          "simulation-thread CPU per step, medians")
    print(f"{'variant':18} {'us/step':>8} {'added':>8} {'alone':>8}")
    before = None
    for name in variants:
        added = "" if before is None or name == "Simulation.step" else f"{med[name] - med[before]:+8.2f}"
        solo = f"{alone[name]:8.2f}" if name in alone else ""
        print(f"{name:18} {med[name]:8.2f} {added:>8} {solo:>8}".rstrip())
        before = name
    print(f"Simulation.step - mj_step: {med['Simulation.step'] - med['mj_step']:.2f} us a step "
          f"(of which the parts alone: {sum(alone.values()):.2f} us)")


def partial_scan(lidar: LidarSensor, backend: Backend) -> Callable[[], object]:
    """One scan of ``lidar``."""
    return lambda: lidar.scan(backend, 0.0)


def _next(count: list[int]) -> int:
    count[0] += 1
    return count[0]


def _alone(fn: Callable[[], object], number: int = 2000) -> float:
    """Microseconds a call of ``fn``, best of 5 (``timeit``)."""
    return min(timeit.repeat(fn, number=number, repeat=5)) / number * 1e6


if __name__ == "__main__":
    main()
