#!/usr/bin/env python3
"""Run the clean-up task end to end over ROS 2: the simulator (headless, with the referee) and the two example
nodes as separate processes. Prints the referee's score table; exits 0 when every trash item is in its correct box.

Usage: .venv/bin/python examples/cleanup/run_task.py [--factor 2.5] [--lockstep] [--backend mujoco] [--timeout 240]
       [--record DIR] [--world worlds/cleanup_random.xml --seed N]
       [--viewer [--viewer-port P] [--viewer-host H] [--viewer-rate HZ] [--viewer-linger S]]

With --viewer the simulator also serves the web viewer: open the URL it prints (``ready: ... viewer at
http://127.0.0.1:8080 ...``) to watch the task being solved, at real time unless --factor says otherwise, in lockstep
unless --no-lockstep (the robot node steps the simulation: what you watch does not depend on the machine's load,
and nothing outruns the node while a browser draws on the same CPUs). After the run the page keeps its last moment,
the result and the score table until Enter here, the page closed, or --viewer-linger S seconds (docs/viewer.md);
--timeout bounds the run, not that wait.
"""

from __future__ import annotations

import argparse
import os
import signal
import subprocess
import sys
import tempfile
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
    ap.add_argument("--factor", type=float, default=None,
                    help="simulation pace, times real time (default 2.5; 1 with --viewer, to follow it)")
    ap.add_argument("--backend", default="mujoco")
    ap.add_argument("--world", default=str(ROOT / "worlds" / "cleanup.xml"),
                    help="the world file (its items and boxes named as in cleanup.xml)")
    ap.add_argument("--seed", type=int, default=None,
                    help="draw the world's <randomize> with this seed (worlds/cleanup_random.xml)")
    ap.add_argument("--timeout", type=float, default=None,
                    help="give up after this many wall seconds (default 240; 600 with --viewer)")
    ap.add_argument("--lockstep", action=argparse.BooleanOptionalAction, default=None,
                    help="the robot node pauses the simulation and steps it itself, one control period at a time "
                         "(default: with --viewer only)")
    ap.add_argument("--domain", type=int, default=None, help="ROS_DOMAIN_ID (default: from the process id)")
    ap.add_argument("--record", default=None, metavar="DIR",
                    help="record the run into DIR (rosbag2, MCAP): sigcore bag info DIR, sigcore replay DIR")
    ap.add_argument("--referee-log", default=None,
                    help="the moderator writes the referee topics it received here (JSON)")
    ap.add_argument("--viewer", action="store_true",
                    help="also serve the web viewer: open the printed URL in a browser to watch the task")
    ap.add_argument("--viewer-port", type=int, default=None, help="the viewer's port (default 8080 or the next free)")
    ap.add_argument("--viewer-host", default=None, help="the address the viewer listens on (default 127.0.0.1)")
    ap.add_argument("--viewer-rate", type=float, default=None, help="scene updates per second (default 30)")
    ap.add_argument("--viewer-linger", type=float, default=None, metavar="S",
                    help="after the run, keep the page up at most S seconds (default: until Enter or the page is "
                         "closed when run from a terminal, not at all otherwise)")
    args = ap.parse_args()
    _take_ctrl_c()
    viewer_args = _viewer_args(args)
    factor = args.factor if args.factor is not None else 1.0 if args.viewer else 2.5
    lockstep = args.lockstep if args.lockstep is not None else args.viewer
    timeout = args.timeout if args.timeout is not None else 600.0 if args.viewer else 240.0
    env = {**os.environ, "ROS_DOMAIN_ID": str(args.domain if args.domain is not None else 100 + os.getpid() % 100),
           "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST", "PYTHONUNBUFFERED": "1"}
    t0 = time.perf_counter()
    # the simulation holds at t = 0 until the robot node publishes commands and the moderator listens to the
    # referee's events (docs/ros2.md, "Readiness"): neither node misses the task's beginning
    sim = _start([sys.executable, "-m", "sigcore", "run", args.world, "--transport", "ros2",
                  "--backend", args.backend, "--factor", str(factor), "--duration", "600", "--quiet",
                  "--wait-for", "/robot_000/cmd_vel", "--wait-for", "/referee/events",
                  *(["--record", args.record] if args.record else []),
                  *(["--seed", str(args.seed)] if args.seed is not None else []), *viewer_args], env)
    moderator = [sys.executable, str(HERE / "moderator_node.py")]
    if args.referee_log:
        moderator += ["--log", args.referee_log]
    nodes = [_start(moderator, env), _start([sys.executable, str(HERE / "robot_node.py"),
                                                     *(["--lockstep"] if lockstep else [])], env)]
    results = Path(viewer_args[-1]) if viewer_args else None
    try:
        code = _wait(sim, t0 + timeout, results)
    except subprocess.TimeoutExpired:
        print(f"run_task: the task did not end within {timeout:g} s of wall time", file=sys.stderr)
        code = 1
    except KeyboardInterrupt:  # Ctrl-C reaches this process only: the others run in sessions of their own
        code = _interrupt(sim)
    try:
        nodes[0].wait(timeout=5)  # the moderator ends by itself once it has the referee's result
    except subprocess.TimeoutExpired:
        pass
    finally:
        for proc in (*nodes, sim):
            _kill(proc)
        if results is not None:
            results.unlink(missing_ok=True)
            results.parent.rmdir()
    print(f"run_task: simulator exited {code}; wall time {time.perf_counter() - t0:.1f} s")
    return code


def _take_ctrl_c() -> None:
    """Ctrl-C (SIGINT) interrupts this process however it was started: a process started in the background by a
    shell, or by a parent that blocked the signal, inherits SIGINT ignored or blocked, and Python then never raises
    KeyboardInterrupt (the Ctrl-C would be lost, and the simulator left running). The simulator and the nodes
    inherit the unblocked mask; they install handlers of their own."""
    signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT, signal.SIGTERM})
    signal.signal(signal.SIGINT, signal.default_int_handler)


def _viewer_args(args: argparse.Namespace) -> list[str]:
    """``sigcore run``'s viewer options for ``--viewer`` (none without it), the results file last: it is written when
    the run has ended, before the page lingers."""
    if not args.viewer:
        given = [name for name in ("viewer_port", "viewer_host", "viewer_rate", "viewer_linger")
                 if getattr(args, name) is not None]
        if given:
            raise SystemExit(f"run_task: --{given[0].replace('_', '-')} needs --viewer")
        return []
    out = ["--viewer"]
    for name in ("viewer_port", "viewer_host", "viewer_rate", "viewer_linger"):
        value = getattr(args, name)
        if value is not None:
            out += [f"--{name.replace('_', '-')}", str(value)]
    results = Path(tempfile.mkdtemp(prefix="run_task_")) / "results.json"
    return [*out, "--results", str(results)]


def _interrupt(sim: subprocess.Popen[bytes]) -> int:
    """Ctrl-C: pass it on to the simulator, which ends its run (or the page's wait after it), prints its results
    and exits with its verdict; the simulator's exit code (130 when it had to be killed)."""
    print("run_task: interrupted; stopping the simulator", file=sys.stderr)
    try:
        if sim.poll() is None:
            os.killpg(sim.pid, signal.SIGINT)
        return sim.wait(timeout=30)
    except (subprocess.TimeoutExpired, KeyboardInterrupt):
        _kill(sim)
        return 130
    except ProcessLookupError:
        return sim.wait()


def _wait(sim: subprocess.Popen[bytes], deadline: float, results: Path | None) -> int:
    """The simulator's exit code. The run must end by ``deadline`` (``perf_counter``); with the viewer its results
    file says it has, and the page may then linger as long as the person looks at it.

    Raises:
        subprocess.TimeoutExpired: the run did not end in time.
    """
    if results is None:
        return sim.wait(timeout=max(0.0, deadline - time.perf_counter()))
    while sim.poll() is None:
        if results.exists():
            return sim.wait()
        if time.perf_counter() > deadline:
            raise subprocess.TimeoutExpired(sim.args, deadline)
        time.sleep(0.2)
    return sim.returncode


if __name__ == "__main__":
    sys.exit(main())
