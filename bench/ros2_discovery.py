"""Discovery time of the ROS 2 graph: every agent's sig_ros endpoints against ``sigros_agents="robots agents"``.

Usage: .venv/bin/python bench/ros2_discovery.py [WORLD] [--rounds R] [--call SERVICE] [--smoke]
       --smoke: 1 round, to check that the bench runs and prints every figure (tests/bench).

For each setting, R rounds (alternating): start ``sigcore run WORLD --paused`` (the simulation is idle, only
discovery is measured), wait for its ``ready:`` line, then start a plain rclpy client process and measure, from
its ``rclpy.init`` (its imports are not counted), the time until its graph holds every topic and service that
the transport plans (``Ros2Transport.plan``, the actions' hidden endpoints aside) and until its first call of
``SERVICE`` (default ``robot_000_get_obj_position``, asking for the robot itself) is answered. Prints the
medians and the planned topic and service counts. The setting is given with ``--ros-args -p sigros_agents:=...``.
Every process runs in one ``ROS_DOMAIN_ID`` of 150-219 (away from the tests' 1-96 and their evaluations' 225-231),
with discovery on this machine only.
"""

from __future__ import annotations

import argparse
import json
import os
import signal
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SETTINGS = {"all": "all", "robots agents": "robots agents"}


def client(expected_file: str, service: str) -> None:
    """The client process: graph discovery and first call times [s] from rclpy.init, as JSON on stdout."""
    import rclpy
    from sigcore_msgs.srv import GetObjPosition

    expected = set(json.loads(Path(expected_file).read_text()))
    t0 = time.perf_counter()
    rclpy.init()
    node = rclpy.create_node("discovery_probe")
    seen = None
    while time.perf_counter() - t0 < 60:
        live = {n for n, _ in node.get_topic_names_and_types()} | {n for n, _ in node.get_service_names_and_types()}
        if expected <= live:
            seen = time.perf_counter() - t0
            break
        rclpy.spin_once(node, timeout_sec=0.01)
    cli = node.create_client(GetObjPosition, service)
    answered = None
    if cli.wait_for_service(timeout_sec=30):
        future = cli.call_async(GetObjPosition.Request(name=""))
        rclpy.spin_until_future_complete(node, future, timeout_sec=30)
        if future.done() and future.result() is not None:
            answered = time.perf_counter() - t0
    print(json.dumps({"seen": seen, "answered": answered, "missing": len(expected - live)}))


def planned(world: Path, selection: str) -> tuple[list[str], int, int]:
    """The full names of the topics and services the transport plans, and their counts."""
    from sigcore_ros2 import Ros2Transport

    from sigcore.sim import Simulation
    from sigcore.world import parse_world

    transport = Ros2Transport()
    transport.configure(["-p", f"sigros_agents:={selection}"])
    plan = [e for e in transport.plan(Simulation(parse_world(world))) if e.kind != "action"]
    return ([e.full_name for e in plan], sum(e.kind == "topic" for e in plan),
            sum(e.kind == "service" for e in plan))


def one_round(world: Path, selection: str, expected_file: str, service: str, env: dict[str, str]) -> dict:
    """Start the simulation, wait for ready, run one client; its result."""
    sim = subprocess.Popen([sys.executable, "-m", "sigcore", "run", str(world), "--paused", "-q",
                            "--ros-args", "-p", f"sigros_agents:={selection}"], env=env, stdout=subprocess.DEVNULL,
                           stderr=subprocess.PIPE, text=True, start_new_session=True)
    try:
        assert sim.stderr is not None
        for line in sim.stderr:
            if line.startswith("ready:"):
                break
        else:
            raise RuntimeError(f"the simulation ended before it was ready ({sim.wait()})")
        done = subprocess.run([sys.executable, __file__, "--client", expected_file, "--call", service], env=env,
                              capture_output=True, text=True, timeout=120)
        lines = [line for line in done.stdout.splitlines() if line.startswith("{")]
        if not lines:
            raise RuntimeError(f"client failed: {done.stderr[-2000:]}")
        return json.loads(lines[-1])
    finally:
        os.killpg(sim.pid, signal.SIGINT)
        try:
            sim.wait(timeout=10)
        except subprocess.TimeoutExpired:
            os.killpg(sim.pid, signal.SIGKILL)
            sim.wait()


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("world", nargs="?", default=str(ROOT / "worlds" / "cleanup.xml"))
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--call", default="robot_000_get_obj_position")
    ap.add_argument("--client", default=None, help=argparse.SUPPRESS)
    ap.add_argument("--smoke", action="store_true", help="1 round: a check that the bench runs, not a measurement")
    args = ap.parse_args()
    if args.smoke:
        args.rounds = 1
    if args.client:
        client(args.client, args.call)
        return
    env = {**os.environ, "ROS_DOMAIN_ID": str(150 + os.getpid() % 70), "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST"}
    world = Path(args.world)
    results: dict[str, list[dict]] = {name: [] for name in SETTINGS}
    counts = {}
    with tempfile.TemporaryDirectory() as tmp:
        files = {}
        for name, selection in SETTINGS.items():
            names, topics, services = planned(world, selection)
            counts[name] = (topics, services)
            files[name] = str(Path(tmp) / f"{name.replace(' ', '_')}.json")
            Path(files[name]).write_text(json.dumps(names))
        for r in range(args.rounds):
            for name, selection in SETTINGS.items():
                res = one_round(world, selection, files[name], args.call, env)
                results[name].append(res)
                print(f"round {r + 1} {name!r}: {res}", flush=True)
    print(f"\n{world.name}, {args.rounds} rounds, load average {os.getloadavg()[0]:.1f}")
    print(f"{'sigros_agents':<16} {'topics':>7} {'services':>9} {'all seen [s]':>13} {'first answer [s]':>17}")
    for name in SETTINGS:
        seen = [r["seen"] for r in results[name] if r["seen"] is not None]
        answered = [r["answered"] for r in results[name] if r["answered"] is not None]
        med = (lambda xs: f"{statistics.median(xs):.2f}" if xs else "n/a")  # noqa: E731
        print(f"{name:<16} {counts[name][0]:>7} {counts[name][1]:>9} {med(seen):>13} {med(answered):>17}")


if __name__ == "__main__":
    main()
