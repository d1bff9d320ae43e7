"""How a ROS 2 node waits for a service's answer: rclpy's ``spin_until_future_complete`` against an executor of its
own spun once at a time (the pattern of ``examples/cleanup/robot_node.py``).

Usage: .venv/bin/python bench/rclpy_calls.py [--calls N] [--rounds R] [--smoke]
       --smoke: 1 round of 5 calls, to check that the bench runs and prints every figure (tests/bench).

Starts ``sigcore run worlds/cleanup.xml --transport ros2 --paused`` (a private ROS_DOMAIN_ID of 150-199, away from
the tests' 1-96; localhost discovery),
then in this process a node like the example robot's (a best-effort ``/clock`` subscription and the sig_ros
clients) calls ``robot_000_get_obj_position`` N times per round with each way of waiting, the ways alternating
for R rounds. Prints the median wall and CPU time per call of each way, and their ratio.

- ``global``: ``rclpy.spin_until_future_complete(node, future)`` (rclpy's global executor; the node is added to
  it and removed again at every call);
- ``own``: ``executor.spin_once(timeout_sec=0.1)`` until the future is done, on a ``SingleThreadedExecutor`` that
  holds the node for its whole life.
"""

from __future__ import annotations

import argparse
import os
import signal
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--calls", type=int, default=100, help="calls per way and round")
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--smoke", action="store_true", help="1 round of 5 calls: a check that the bench runs, not a "
                    "measurement")
    args = ap.parse_args()
    if args.smoke:
        args.rounds, args.calls = 1, 5
    os.environ.update(ROS_DOMAIN_ID=str(150 + os.getpid() % 50), ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST")
    sim = subprocess.Popen([sys.executable, "-m", "sigcore", "run", str(ROOT / "worlds" / "cleanup.xml"),
                            "--transport", "ros2", "--paused", "--quiet"], start_new_session=True,
                           stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        return measure(args.calls, args.rounds)
    finally:
        os.killpg(sim.pid, signal.SIGINT)
        sim.wait(timeout=30)


def measure(calls: int, rounds: int) -> int:
    import rclpy
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.qos import QoSProfile, ReliabilityPolicy
    from rosgraph_msgs.msg import Clock
    from sigcore_msgs.srv import GetObjPosition, GetRotation

    rclpy.init()
    node = rclpy.create_node("bench_calls")
    node.create_subscription(Clock, "/clock", lambda _m: None, QoSProfile(depth=10,
                                                                           reliability=ReliabilityPolicy.BEST_EFFORT))
    position = node.create_client(GetObjPosition, "robot_000_get_obj_position")
    node.create_client(GetRotation, "robot_000_get_rotation")
    if not position.wait_for_service(timeout_sec=60.0):
        print("the simulator's robot_000_get_obj_position did not appear within 60 s", file=sys.stderr)
        return 1
    own = SingleThreadedExecutor()

    def by_global() -> None:
        future = position.call_async(GetObjPosition.Request(name=""))
        rclpy.spin_until_future_complete(node, future, timeout_sec=10.0)
        assert future.done()

    def by_own() -> None:
        future = position.call_async(GetObjPosition.Request(name=""))
        if node.executor is not own:
            own.add_node(node)
        while not future.done():
            own.spin_once(timeout_sec=0.1)

    times: dict[str, list[tuple[float, float]]] = {"global": [], "own": []}
    for r in range(rounds):
        for name, way in (("global", by_global), ("own", by_own)) if r % 2 == 0 else \
                (("own", by_own), ("global", by_global)):
            if name == "global" and node.executor is own:
                own.remove_node(node)
            way()  # warm
            wall, cpu = time.perf_counter(), time.process_time()
            for _ in range(calls):
                way()
            times[name].append(((time.perf_counter() - wall) / calls * 1e3, (time.process_time() - cpu) / calls * 1e3))
    med = {k: (statistics.median(w for w, _ in v), statistics.median(c for _, c in v)) for k, v in times.items()}
    for name, (wall, cpu) in med.items():
        print(f"{name:7} {wall:7.2f} ms wall  {cpu:7.2f} ms CPU per call (median of {rounds} rounds x {calls})")
    print(f"global / own: {med['global'][0] / med['own'][0]:.1f}x wall, {med['global'][1] / med['own'][1]:.1f}x CPU")
    node.destroy_node()
    rclpy.try_shutdown()
    return 0


if __name__ == "__main__":
    sys.exit(main())
