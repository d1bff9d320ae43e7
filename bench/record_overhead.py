"""Cost of recording (issue 15): the clean-up world's throughput with ``--record`` (every topic) against without.

Usage: .venv/bin/python bench/record_overhead.py [WORLD] [--chunk N] [--rounds R] [--transports ros2,none]
       [--smoke]
       --smoke: 1 round of 100 steps, to check that the bench runs and prints every figure (tests/bench).

Per transport, two simulations of WORLD (default worlds/cleanup.xml) with the scripted robot
(``robot_000=cleanup.robot``, so that it drives, grasps and scores) are built in this process: ``plain`` and
``recording`` (a :class:`sigcore.record.Recorder` on it, every topic, as ``sigcore run --record DIR``). With ``ros2``
each has its own ROS 2 transport, started once: the idiomatic topics at their default rates (/clock by its policy,
/tf, odometry and joint states at 50 Hz, the entity transforms at 10 Hz, the lidar at 10 Hz), every sig_ros
endpoint, the declared publications; the recorder takes all of them plus the ground truth at 30 Hz and the input
log. With ``none``, no transport: the recorder alone (declared publications, whose event sources it switches on,
the ground truth). The ROS 2 transports are in ``ROS_DOMAIN_ID`` if it is set, else in one of 150-219 (away from the
tests' 1-96 and their evaluations' 225-231), with discovery on this machine only. Both simulations advance in
lockstep, the same N steps per round (``transport.service`` then ``sim.step``, as ``sigcore.sim.run`` does), as fast
as possible; the order alternates every round, so a burst of load from elsewhere falls on both. Each round's time is
measured as wall-clock and as CPU time of this thread (which a busy neighbour does not inflate), and the ratio is
throughput with recording over throughput without: the total of all rounds, and the median of the per-round ratios
with its range.

Target (issue 15): ratio >= 0.9 for the idiomatic topics at their default rates (``ros2``).
"""

from __future__ import annotations

import argparse
import os
import shutil
import statistics
import tempfile
import time
from pathlib import Path
from typing import Any

from sigcore.record import Recorder
from sigcore.sim import Simulation
from sigcore.world import parse_world

ROOT = Path(__file__).resolve().parent.parent
DOMAIN = 150 + os.getpid() % 70
"""The ROS 2 domain when ``ROS_DOMAIN_ID`` is not set: one of 150-219 (the tests use 1-96, their evaluations
225-231)."""


def _build(world: Path, transport: str, bag: Path | None) -> tuple[Simulation, Any, Recorder | None]:
    sim = Simulation(parse_world(world), "mujoco", {"robot_000": "cleanup.robot"})
    recorder = Recorder(sim, bag) if bag is not None else None  # before the transport, as sigcore run does
    t: Any = None
    if transport == "ros2":
        from sigcore_ros2 import Ros2Transport

        t = Ros2Transport()
    sim.start()
    if t is not None:
        t.start(sim)
    return sim, t, recorder


def _advance(sim: Simulation, transport: Any, steps: int) -> tuple[float, float]:
    """``steps`` steps as the runner takes them; (wall, thread CPU) seconds."""
    w, c = time.perf_counter(), time.thread_time()
    for _ in range(steps):
        if transport is not None:
            transport.service(0.0)
        sim.step()
    return time.perf_counter() - w, time.thread_time() - c


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("world", nargs="?", type=Path, default=ROOT / "worlds" / "cleanup.xml")
    ap.add_argument("--chunk", type=int, default=1000, help="steps per simulation per round")
    ap.add_argument("--rounds", type=int, default=40, help="rounds (chunk x rounds < 46000: the task ends there)")
    ap.add_argument("--transports", default="ros2,none")
    ap.add_argument("--smoke", action="store_true", help="1 round of 100 steps: a check that the bench runs, not a "
                    "measurement")
    args = ap.parse_args()
    if args.smoke:
        args.rounds, args.chunk = 1, 100
    os.environ.setdefault("ROS_DOMAIN_ID", str(DOMAIN))
    os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
    tmp = Path(tempfile.mkdtemp(prefix="record_bench_"))
    print(f"{args.world.name}: {args.rounds} rounds of {args.chunk} steps per simulation; load average "
          f"{os.getloadavg()[0]:.2f}; {time.strftime('%Y-%m-%d %H:%M')}", flush=True)
    try:
        for transport in args.transports.split(","):
            plain = _build(args.world, transport, None)
            rec = _build(args.world, transport, tmp / f"bag_{transport}")
            times: dict[str, list[tuple[float, float]]] = {"plain": [], "recording": []}
            _advance(plain[0], plain[1], 200)  # warm-up: first steps, first publications
            _advance(rec[0], rec[1], 200)
            for r in range(args.rounds):
                order = [("plain", plain), ("recording", rec)]
                for name, (sim, t, _) in order if r % 2 == 0 else order[::-1]:
                    times[name].append(_advance(sim, t, args.chunk))
            recorder = rec[2]
            assert recorder is not None
            messages = recorder.messages
            for sim, t, r_ in (plain, rec):
                if t is not None:
                    t.stop()
                sim.stop()
                if r_ is not None:
                    r_.close()
            size = sum(f.stat().st_size for f in (tmp / f"bag_{transport}").glob("*.mcap"))
            steps = args.rounds * args.chunk
            for i, what in ((0, "wall"), (1, "CPU")):
                a = [x[i] for x in times["plain"]]
                b = [x[i] for x in times["recording"]]
                ratios = [pa / pb for pa, pb in zip(a, b, strict=True)]
                print(f"{transport:5} {what:4}: plain {steps / sum(a):7.0f} steps/s, recording {steps / sum(b):7.0f} "
                      f"steps/s; ratio {sum(a) / sum(b):.3f} (per round: median {statistics.median(ratios):.3f}, "
                      f"range {min(ratios):.3f}-{max(ratios):.3f})", flush=True)
            print(f"{transport:5} recorded {messages} messages in {steps + 200} steps, {size / 1e6:.1f} MB "
                  f"({size / (steps + 200) * 500 / 1e3:.0f} kB per simulated second)", flush=True)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    main()
