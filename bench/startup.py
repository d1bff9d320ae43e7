"""Start-up time against the number of entities, with and without the ROS 2 transport (issue 28, item 9).

Usage: .venv/bin/python bench/startup.py [--counts 30 100 300 1000 3000] [--transports none ros2]
       [--timeout 120] [--repeats 1] [--sigros-agents WORDS] [--smoke]
       --smoke: 30 boxes only (--counts 30), to check that the bench runs and prints every figure (tests/bench).

For each count N a world of N static boxes (a grid, 0.1 m cubes 0.5 m apart; no robot) is written to a temporary
directory and ``sigcore run WORLD --steps 10`` is started as a new process, with ``--transport none`` or with the
ROS 2 transport (``--transport ros2``, with ``--ros-args -p sigros_agents:=WORDS`` when ``--sigros-agents`` is
given). The figure is the wall time from starting the process to its exit (interpreter start, parsing, building,
the transport's endpoints, 10 steps, closing): what a user waiting for ``sigcore run`` sees. A run that has not
ended after ``--timeout`` seconds is killed (its process group) and reported as ``> T``. The ROS 2 runs also give
the number of endpoints the transport plans for the world (``Ros2Transport.plan``). Each ROS 2 run has its own
``ROS_DOMAIN_ID`` (101-119, away from the tests' 1-96 and ``sigcore eval``'s 120-232) with discovery on this
machine only. Medians over ``--repeats``; a run that exits with an error is reported as ``exit CODE`` (its stderr
is printed).
"""

from __future__ import annotations

import argparse
import os
import random
import signal
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SIGCORE = str(Path(sys.executable).with_name("sigcore"))
COUNTS = (30, 100, 300, 1000, 3000)
SPACING = 0.5
"""Distance between neighbouring boxes of the grid [m]."""


def world_text(count: int) -> str:
    """A world of ``count`` static 0.1 m boxes on a square grid ``SPACING`` apart."""
    side = max(1, int(count ** 0.5 + 0.999))
    lines = ['<world name="boxes" timestep="0.002">']
    for i in range(count):
        x, y = (i % side) * SPACING, (i // side) * SPACING
        lines.append(f'  <object name="box_{i:05d}" shape="box" size="0.1 0.1 0.1" static="true" '
                     f'pose="{x:.2f} {y:.2f} 0.05"/>')
    lines.append("</world>")
    return "\n".join(lines) + "\n"


def run_once(world: Path, transport: str, sigros_agents: str | None, timeout: float) -> float | None:
    """Wall time [s] of ``sigcore run WORLD --steps 10`` to its exit, or None when it was still running after
    ``timeout`` seconds (then killed)."""
    cmd = [SIGCORE, "run", str(world), "--steps", "10", "--transport", transport]
    if transport == "ros2" and sigros_agents is not None:
        cmd += ["--ros-args", "-p", f"sigros_agents:={sigros_agents}"]
    env = dict(os.environ, ROS_DOMAIN_ID=str(random.randint(101, 119)), ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST")
    t0 = time.perf_counter()
    proc = subprocess.Popen(cmd, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                            start_new_session=True)
    try:
        _, err = proc.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()
        return None
    elapsed = time.perf_counter() - t0
    if proc.returncode != 0:
        raise RunFailed(f"{' '.join(cmd)} exited {proc.returncode}:\n{err[-1500:]}", proc.returncode)
    return elapsed


class RunFailed(Exception):
    """A run exited with an error (its command, exit code and the end of its stderr)."""

    def __init__(self, message: str, code: int) -> None:
        super().__init__(message)
        self.code = code


def planned_endpoints(world: Path, sigros_agents: str | None) -> int:
    """The number of endpoints ``Ros2Transport.plan`` lists for ``world``."""
    from sigcore_ros2 import Ros2Transport
    from sigcore_ros2.config import Ros2Config

    from sigcore.sim import Simulation
    from sigcore.world import parse_world

    config = None if sigros_agents is None else Ros2Config(sigros_agents=sigros_agents)  # type: ignore[arg-type]
    return len(Ros2Transport(config).plan(Simulation(parse_world(world))))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--counts", type=int, nargs="+", default=list(COUNTS), help="numbers of boxes")
    parser.add_argument("--transports", nargs="+", default=["none", "ros2"], choices=["none", "ros2"])
    parser.add_argument("--timeout", type=float, default=120.0, help="give up on one run after this long [s]")
    parser.add_argument("--repeats", type=int, default=1, help="runs per case (median)")
    parser.add_argument("--sigros-agents", default=None,
                        help="sigros_agents for the ROS 2 runs (default: the world's default)")
    parser.add_argument("--smoke", action="store_true", help="30 boxes only: a check that the bench runs, not a "
                        "measurement")
    args = parser.parse_args()
    if args.smoke:
        args.counts = [30]
    rows = []
    with tempfile.TemporaryDirectory(prefix="sigcore-startup-") as tmp:
        for count in args.counts:
            world = Path(tmp) / f"boxes_{count}.xml"
            world.write_text(world_text(count))
            row = {"N": str(count)}
            for transport in args.transports:
                try:
                    times = [run_once(world, transport, args.sigros_agents, args.timeout)
                             for _ in range(args.repeats)]
                except RunFailed as e:
                    print(e, file=sys.stderr)
                    row[transport] = f"exit {e.code}"
                else:
                    done = [t for t in times if t is not None]
                    row[transport] = (f"{statistics.median(done):.1f}" if len(done) == len(times)
                                      else f"> {args.timeout:g}")
                print(f"N={count} {transport}: {row[transport]} s", file=sys.stderr, flush=True)
            if "ros2" in args.transports:
                row["endpoints"] = str(planned_endpoints(world, args.sigros_agents))
            rows.append(row)
    head = ["N"] + [f"{t} [s]" for t in args.transports] + (["ROS 2 endpoints"] if "ros2" in args.transports else [])
    keys = ["N"] + args.transports + (["endpoints"] if "ros2" in args.transports else [])
    print(f"sigcore run boxes_N.xml --steps 10, wall time to exit (median of {args.repeats}; "
          f"sigros_agents: {args.sigros_agents or 'default'})")
    print("| " + " | ".join(head) + " |")
    print("|" + "---|" * len(head))
    for row in rows:
        print("| " + " | ".join(row[k] for k in keys) + " |")


if __name__ == "__main__":
    main()
