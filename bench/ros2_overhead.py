"""Cost of the ROS 2 transport, in one run: real-time factor and service round trip.

Usage: .venv/bin/python bench/ros2_overhead.py [WORLD] [--steps N] [--rounds R] [--calls C] [--clock-rate HZ]
                                             [--clock-wall-limit HZ] [--smoke]
       --smoke: 1 round of 200 steps and 10 calls per service, to check that the bench runs (tests/bench).

1. Real-time factor of WORLD (default worlds/cleanup.xml) run by sigcore's runner with the ROS 2 transport on
   (/clock by the default policy: every step but at most --clock-wall-limit per wall second besides the one
   before each state message; /tf + odom + joint_states at 50 Hz, the lidar at its rate, every
   sig_ros endpoint) against raw ``mj_step`` on the same compiled model; rounds alternate. Twice: with nobody
   subscribed, then with a subscriber process on /clock (best effort, as a use_sim_time node), /tf, odom,
   joint_states and the scan, so the messages are really delivered. Wall-clock and simulation-thread CPU time
   are both reported: on a shared machine the wall-clock figure includes time the process was not scheduled.
2. Round trip of ``robot_000_get_obj_position`` (answered between steps of the running simulation) against a
   bare rclpy service of the same type in another process (a SingleThreadedExecutor answering a constant), from
   one client process; blocks of calls alternate between the two. Median and 99th percentile.

Every process runs in ``ROS_DOMAIN_ID`` if it is set, else in one of 150-219 (away from the tests' 1-96 and their
evaluations' 225-231), with discovery on this machine only.

Targets (issue 11): real-time factor ratio >= 0.6 with nobody subscribed and >= 0.5 with the subscriber process,
at the default settings; round-trip median ratio <= 2.
"""

from __future__ import annotations

import argparse
import json
import os
import signal
import statistics
import subprocess
import sys
import threading
import time
from pathlib import Path

import mujoco
from sigcore_ros2 import Ros2Config, Ros2Transport
from sigcore_ros2.config import CLOCK_WALL_LIMIT

from sigcore.sim import Simulation
from sigcore.sim.runner import run
from sigcore.transport import Transport
from sigcore.world import parse_world

ROOT = Path(__file__).resolve().parent.parent

BARE_SERVER = """
import rclpy
from sigcore_msgs.srv import GetObjPosition
rclpy.init()
node = rclpy.create_node("bare_server")
def cb(req, res):
    res.pos_x, res.pos_y, res.pos_z, res.success = 1.0, 2.0, 3.0, True
    return res
node.create_service(GetObjPosition, "/bare_get_obj_position", cb)
rclpy.spin(node)
"""

LISTENER = """
import signal, sys, rclpy
from rclpy.qos import QoSProfile, ReliabilityPolicy, qos_profile_sensor_data
from rosgraph_msgs.msg import Clock
from tf2_msgs.msg import TFMessage
from nav_msgs.msg import Odometry
from sensor_msgs.msg import JointState, LaserScan
rclpy.init()
node = rclpy.create_node("listener")
counts = {}
def counter(name):
    counts[name] = 0
    def cb(_):
        counts[name] += 1
    return cb
robot, lidar = sys.argv[1], sys.argv[2]
# /clock as every ROS node with use_sim_time subscribes to it (rclpy/rclcpp TimeSource: best effort, depth 1)
node.create_subscription(Clock, "/clock", counter("clock"),
                         QoSProfile(depth=1, reliability=ReliabilityPolicy.BEST_EFFORT))
node.create_subscription(TFMessage, "/tf", counter("tf"), 10)
node.create_subscription(Odometry, f"/{robot}/odom", counter("odom"), 10)
node.create_subscription(JointState, f"/{robot}/joint_states", counter("joint_states"), 10)
node.create_subscription(LaserScan, f"/{robot}/{lidar}", counter("scan"), qos_profile_sensor_data)
stop = []
signal.signal(signal.SIGTERM, lambda *_: stop.append(1))
while not stop:
    rclpy.spin_once(node, timeout_sec=0.1)
print(counts, flush=True)
"""

CLIENT = """
import json, sys, time, rclpy
from rclpy.executors import SingleThreadedExecutor
from sigcore_msgs.srv import GetObjPosition
rclpy.init()
node = rclpy.create_node("rtt_client")
executor = SingleThreadedExecutor()
executor.add_node(node)
names = sys.argv[1].split(",")
calls = int(sys.argv[2])
clients = {n: node.create_client(GetObjPosition, n) for n in names}
for n, c in clients.items():
    if not c.wait_for_service(timeout_sec=30):
        print(json.dumps({"error": f"no service {n}"})); sys.exit(1)
def once(c):
    t = time.perf_counter()
    f = c.call_async(GetObjPosition.Request(name="can_0"))
    while not f.done():
        executor.spin_once(timeout_sec=1.0)
    assert f.done() and f.result().success, f.result()
    return (time.perf_counter() - t) * 1e3
for c in clients.values():
    for _ in range(50):
        once(c)
out = {n: [] for n in names}
block = max(1, calls // 10)
for _ in range(10):
    for n, c in clients.items():
        out[n] += [once(c) for _ in range(block)]
print(json.dumps(out), flush=True)
"""


class _Keep(Transport):
    """Delegates ``service`` to a started transport and leaves it started across runs."""

    name = "keep"

    def __init__(self, inner: Ros2Transport) -> None:
        self.inner = inner

    def start(self, sim: Simulation) -> None:
        pass

    def service(self, timeout: float) -> None:
        self.inner.service(timeout)

    def stop(self) -> None:
        pass


def _p(values: list[float], q: float) -> float:
    s = sorted(values)
    return s[min(len(s) - 1, int(q * len(s)))]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("world", nargs="?", default=str(ROOT / "worlds" / "cleanup.xml"))
    ap.add_argument("--steps", type=int, default=5000, help="steps per round")
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--calls", type=int, default=1000, help="round trips per service")
    ap.add_argument("--clock-rate", type=float, default=0.0, help="/clock rate [Hz]; 0: every step")
    ap.add_argument("--clock-wall-limit", type=float, default=CLOCK_WALL_LIMIT,
                    help="most /clock messages per wall second [Hz]; 0: no limit (every step)")
    ap.add_argument("--smoke", action="store_true", help="1 round of 200 steps, 10 calls per service: a check that "
                    "the bench runs, not a measurement")
    args = ap.parse_args()
    if args.smoke:
        args.rounds, args.steps, args.calls = 1, 200, 10

    env = dict(os.environ)
    env.setdefault("ROS_DOMAIN_ID", str(150 + os.getpid() % 70))
    env.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
    os.environ.update(env)

    world = parse_world(args.world)
    sim = Simulation(world, "mujoco")
    robot = next(a.name for a in world.agents if a.kind == "robot")
    lidar = sim.entities.lidars[0].model.name
    transport = Ros2Transport(Ros2Config(clock_rate=args.clock_rate, clock_wall_limit=args.clock_wall_limit,
                                         state_rate=50.0))
    t0 = time.perf_counter()
    transport.start(sim)
    started = time.perf_counter() - t0
    model = sim.backend.model  # type: ignore[attr-defined]
    raw = mujoco.MjData(model)
    raw.qpos[:] = sim.backend.data.qpos  # type: ignore[attr-defined]
    mujoco.mj_forward(model, raw)
    procs: list[subprocess.Popen[str]] = []

    def spawn(code: str, *argv: str) -> subprocess.Popen[str]:
        p = subprocess.Popen([sys.executable, "-c", code, *argv], env=env, stdout=subprocess.PIPE, text=True,
                             start_new_session=True)
        procs.append(p)
        return p

    try:
        keep = _Keep(transport)
        run(sim, duration=1.0, transport=keep)  # warm-up
        for _ in range(200):
            mujoco.mj_step(model, raw)

        def rounds() -> dict[str, list[float]]:
            """Alternating rounds: wall steps/s and simulation-thread CPU [us/step] of raw and ros2."""
            out: dict[str, list[float]] = {"raw": [], "ros2": [], "raw_cpu": [], "ros2_cpu": []}
            for _ in range(args.rounds):
                t, c = time.perf_counter(), time.thread_time()
                for _ in range(args.steps):
                    mujoco.mj_step(model, raw)
                out["raw"].append(args.steps / (time.perf_counter() - t))
                out["raw_cpu"].append((time.thread_time() - c) / args.steps * 1e6)
                c = time.thread_time()
                rep = run(sim, steps=args.steps, transport=keep)
                out["ros2"].append(rep.steps / rep.wall_time)
                out["ros2_cpu"].append((time.thread_time() - c) / args.steps * 1e6)
            return out

        quiet = rounds()  # nobody subscribed
        listener = spawn(LISTENER, robot, lidar)
        # the subscriber process needs a second or more to start and match: until every publisher it listens to
        # has matched it, a round would measure the unsubscribed case
        standard = transport.standard
        assert standard is not None
        listened = [standard.clock_pub, standard.tf_pub, standard.odom_pub[robot], standard.joint_pub[robot],
                    standard.scan_pub[(robot, lidar)]]
        deadline = time.monotonic() + 30.0
        while any(pub.get_subscription_count() == 0 for pub in listened):
            if time.monotonic() > deadline or listener.poll() is not None:
                raise SystemExit("the subscriber process did not match the publishers within 30 s")
            run(sim, steps=100, transport=keep)
        run(sim, duration=2.0, transport=keep)  # let the subscriber settle
        loaded = rounds()
        listener.send_signal(signal.SIGTERM)
        counts = listener.communicate(timeout=10)[0].strip()

        # round trips, with the simulation running as fast as it can meanwhile
        spawn(BARE_SERVER)
        sim_srv = f"/{robot}_get_obj_position"
        client = spawn(CLIENT, f"{sim_srv},/bare_get_obj_position", str(args.calls))
        sim.control.rearm()

        def watch() -> None:
            client.wait()
            sim.control.stop("bench")

        threading.Thread(target=watch, daemon=True).start()
        rtt_run = run(sim, transport=keep)
        result = json.loads(client.communicate(timeout=10)[0])
        sim.control.rearm()
    finally:
        for p in procs:
            if p.poll() is None:
                os.killpg(p.pid, signal.SIGKILL)
        transport.stop()

    dt = world.timestep
    print(f"world: {args.world}  timestep {dt} s  endpoints: {len(transport.endpoints)} (created in {started:.2f} s)")
    limit = f", at most {args.clock_wall_limit:g}/s of wall time" if args.clock_wall_limit > 0 else ""
    print(f"/clock: {'every step' if args.clock_rate <= 0 else f'{args.clock_rate:g} Hz'}{limit};  "
          f"tf/odom/joint_states 50 Hz;  lidar {sim.entities.lidars[0].model.rate:g} Hz;  "
          f"{args.rounds} alternating rounds x {args.steps} steps; load average {os.getloadavg()[0]:.1f}")
    for label, r, target in (("no subscriber", quiet, 0.6),
                             ("a subscriber process on /clock, /tf, odom, joint_states, scan", loaded, 0.5)):
        med = {k: statistics.median(v) for k, v in r.items()}
        print(f" with {label}:")
        print(f"  raw mj_step                {med['raw']:8.0f} steps/s  {1e6 / med['raw']:6.1f} us/step "
              f"(cpu {med['raw_cpu']:5.1f})  real-time factor {med['raw'] * dt:6.1f}")
        print(f"  sigcore + ROS 2 transport  {med['ros2']:8.0f} steps/s  {1e6 / med['ros2']:6.1f} us/step "
              f"(cpu {med['ros2_cpu']:5.1f})  real-time factor {med['ros2'] * dt:6.1f}")
        print(f"  ratio (target >= {target:g}): wall {med['ros2'] / med['raw']:.3f}   "
              f"simulation-thread cpu {med['raw_cpu'] / med['ros2_cpu']:.3f}")
    print(f"  messages received by the subscriber: {counts}")
    s, b = result[sim_srv], result["/bare_get_obj_position"]
    print(f"round trip of {sim_srv} vs a bare rclpy service ({len(s)} calls each, alternating blocks; "
          f"simulation running at real-time factor {rtt_run.real_time_factor:.1f} meanwhile):")
    print(f"  sigcore  median {statistics.median(s):6.3f} ms   p99 {_p(s, 0.99):6.3f} ms")
    print(f"  bare     median {statistics.median(b):6.3f} ms   p99 {_p(b, 0.99):6.3f} ms")
    print(f"  ratio    median {statistics.median(s) / statistics.median(b):.2f}   p99 {_p(s, 0.99) / _p(b, 0.99):.2f}"
          "   (target <= 2)")


if __name__ == "__main__":
    main()
