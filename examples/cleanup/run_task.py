#!/usr/bin/env python3
"""Run the clean-up task end to end over ROS 2: the simulator (headless, with the referee) and the two example
nodes as separate processes. Prints the referee's score table; exits 0 when every trash item is in its correct box.

Usage: .venv/bin/python examples/cleanup/run_task.py [--factor 2.5] [--lockstep] [--backend mujoco] [--timeout 240]
       [--record DIR] [--world worlds/cleanup_random.xml --seed N]
"""

from __future__ import annotations

import argparse
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent.parent


def _start(args: list[str], env: dict[str, str], **kwargs: object) -> subprocess.Popen[bytes]:
    return subprocess.Popen(args, env=env, start_new_session=True, **kwargs)  # type: ignore[call-overload]


def _kill(proc: subprocess.Popen[bytes]) -> None:
    if proc.poll() is None:
        os.killpg(proc.pid, signal.SIGINT)
        try:
            proc.wait(timeout=5)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--factor", type=float, default=2.5, help="simulation pace, times real time")
    ap.add_argument("--backend", default="mujoco")
    ap.add_argument("--world", default=str(ROOT / "worlds" / "cleanup.xml"),
                    help="the world file (its items and boxes named as in cleanup.xml)")
    ap.add_argument("--seed", type=int, default=None,
                    help="draw the world's <randomize> with this seed (worlds/cleanup_random.xml)")
    ap.add_argument("--timeout", type=float, default=240.0, help="give up after this many wall seconds")
    ap.add_argument("--lockstep", action="store_true",
                    help="the robot node pauses the simulation and steps it itself, one control period at a time")
    ap.add_argument("--domain", type=int, default=None, help="ROS_DOMAIN_ID (default: from the process id)")
    ap.add_argument("--record", default=None, metavar="DIR",
                    help="record the run into DIR (rosbag2, MCAP): sigcore bag info DIR, sigcore replay DIR")
    ap.add_argument("--referee-log", default=None,
                    help="the moderator writes the referee topics it received here (JSON)")
    args = ap.parse_args()
    env = {**os.environ, "ROS_DOMAIN_ID": str(args.domain if args.domain is not None else 100 + os.getpid() % 100),
           "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST", "PYTHONUNBUFFERED": "1"}
    t0 = time.perf_counter()
    # the simulation holds at t = 0 until the robot node publishes commands and the moderator listens to the
    # referee's events (docs/ros2.md, "Readiness"): neither node misses the task's beginning
    sim = _start([sys.executable, "-m", "sigcore", "run", args.world, "--transport", "ros2",
                  "--backend", args.backend, "--factor", str(args.factor), "--duration", "600", "--quiet",
                  "--wait-for", "/robot_000/cmd_vel", "--wait-for", "/referee/events",
                  *(["--record", args.record] if args.record else []),
                  *(["--seed", str(args.seed)] if args.seed is not None else [])], env)
    moderator = [sys.executable, str(HERE / "moderator_node.py")]
    if args.referee_log:
        moderator += ["--log", args.referee_log]
    nodes = [_start(moderator, env), _start([sys.executable, str(HERE / "robot_node.py"),
                                                     *(["--lockstep"] if args.lockstep else [])], env)]
    try:
        code = sim.wait(timeout=args.timeout)
    except subprocess.TimeoutExpired:
        print(f"run_task: the task did not end within {args.timeout:g} s of wall time", file=sys.stderr)
        code = 1
    try:
        nodes[0].wait(timeout=5)  # the moderator ends by itself once it has the referee's result
    except subprocess.TimeoutExpired:
        pass
    finally:
        for proc in (*nodes, sim):
            _kill(proc)
    print(f"run_task: simulator exited {code}; wall time {time.perf_counter() - t0:.1f} s")
    return code


if __name__ == "__main__":
    sys.exit(main())
