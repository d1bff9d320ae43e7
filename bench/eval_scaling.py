"""Episodes per hour of ``sigcore eval``: 1 worker against K workers on this machine, and K local workers against a
local Ray cluster of K CPUs (bound to 127.0.0.1).

Usage: .venv/bin/python bench/eval_scaling.py [--episodes N] [--workers K] [--mode ros2|controller] [--no-ray]
           [--rounds R] [--duration S] [--smoke]
       --smoke: 1 round of 1 episode cut at 1 simulated s, to check that the bench runs (tests/bench).

Each condition is one whole ``sigcore eval`` process over the same N seeded episodes (seeds 0..N-1), timed from its
start to its end (start-up, every episode and the summary); episodes per hour = N / that time. The conditions run
one after the other in the order 1 worker, K workers, Ray, then in the reverse order, and so on (R rounds, default 2,
so that a change of the machine's speed during the bench shows): the figures are the medians. An episode lasts until
the task's end, or at most ``--duration`` simulated seconds (``sigcore eval --duration``).

- ``ros2`` (default): the example ROS 2 solution, ``examples/cleanup/robot_node.py --lockstep``, on
  ``tests/data/eval/cleanup_one.xml`` (one trash item drawn on a table, the robot's start drawn);
- ``controller``: the in-process scripted controller (``--controller robot_000=cleanup.robot``, no ROS 2) on
  ``worlds/cleanup_random.xml``.

Prints per condition: episodes, successes, the mean simulated and wall time of an episode, the evaluation's wall
time and episodes per hour; then the efficiency of K workers (rate_K / (K rate_1)) and the ratio Ray / local.

The Ray cluster (``ray start --head``, bound to 127.0.0.1) runs in a process group of its own, which is killed at the
end: ``ray stop`` would stop every Ray cluster on the machine, a test's too.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import signal
import socket
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
NODE = f"{sys.executable} {ROOT / 'examples' / 'cleanup' / 'robot_node.py'} --lockstep"


def evaluation(mode: str, episodes: int, out: Path, extra: list[str]) -> dict:
    if mode == "ros2":
        what = [str(ROOT / "tests" / "data" / "eval" / "cleanup_one.xml"), "--solution", NODE,
                "--wait-for", "/robot_000/cmd_vel"]
    else:
        what = [str(ROOT / "worlds" / "cleanup_random.xml"), "--controller", "robot_000=cleanup.robot"]
    t0 = time.perf_counter()
    r = subprocess.run([sys.executable, "-m", "sigcore", "eval", *what, "--episodes", str(episodes), "--timeout",
                        "300", "--out", str(out), *extra], capture_output=True, text=True, cwd=ROOT)
    wall = time.perf_counter() - t0
    if r.returncode != 0:
        sys.exit(f"sigcore eval {' '.join(extra)} failed ({r.returncode}):\n{r.stdout[-2000:]}{r.stderr[-2000:]}")
    summary = json.loads((out / "summary.json").read_text())
    return {"wall": wall, "per_hour": episodes / wall * 3600, "succeeded": summary["succeeded"],
            "sim_mean": summary["sim_time_mean"], "episode_wall": summary["wall_time_mean"],
            "nodes": summary.get("nodes")}


def ray_cluster(cpus: int) -> tuple[int, str, str]:
    """Start a local Ray cluster of ``cpus`` CPUs: (the process group of its processes, its address, its temporary
    folder)."""
    ray = shutil.which("ray", path=str(Path(sys.executable).parent))
    if ray is None:
        sys.exit("Ray is not installed: bash scripts/setup.sh installs it (or --no-ray)")
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    temp = tempfile.mkdtemp(prefix="ray", dir="/tmp")
    start = subprocess.Popen([ray, "start", "--head", "--node-ip-address=127.0.0.1", f"--port={port}",
                              f"--num-cpus={cpus}", "--include-dashboard=false", f"--temp-dir={temp}",
                              "--disable-usage-stats"], stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                             start_new_session=True, env={**os.environ, "RAY_USAGE_STATS_ENABLED": "0",
                                                          "RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER": "0"})
    said, _ = start.communicate()
    if start.returncode != 0:
        stop_ray(start.pid, temp)
        sys.exit(f"ray start failed ({start.returncode}):\n{said[-3000:]}")
    return start.pid, f"127.0.0.1:{port}", temp


def stop_ray(group: int, temp: str) -> None:
    """Kill the Ray cluster's process group (what ``ray stop --force`` does to every cluster) and remove its
    folder."""
    try:
        os.killpg(group, signal.SIGKILL)
    except ProcessLookupError:
        pass
    shutil.rmtree(temp, ignore_errors=True)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--episodes", type=int, default=4)
    ap.add_argument("--workers", type=int, default=os.cpu_count() or 2, help="K (default: the core count)")
    ap.add_argument("--mode", choices=("ros2", "controller"), default="ros2")
    ap.add_argument("--no-ray", action="store_true")
    ap.add_argument("--rounds", type=int, default=2, help="rounds of every condition (the order reversed each time)")
    ap.add_argument("--duration", type=float, default=None,
                    help="at most this many simulated seconds per episode [s] (default: until the task's end)")
    ap.add_argument("--smoke", action="store_true", help="1 round of 1 episode cut at 1 simulated s: a check that "
                    "the bench runs, not a measurement")
    args = ap.parse_args()
    if args.smoke:
        args.rounds, args.episodes, args.duration = 1, 1, 1.0
    k = args.workers
    cut = [] if args.duration is None else ["--duration", f"{args.duration:g}"]
    conditions = {"1 worker": ["--workers", "1", *cut], f"{k} workers": ["--workers", str(k), *cut]}
    cluster = None
    if not args.no_ray:
        cluster = ray_cluster(k)
        conditions[f"Ray, {k} CPUs"] = ["--ray", cluster[1], *cut]
    results: dict[str, list[dict]] = {name: [] for name in conditions}
    try:
        with tempfile.TemporaryDirectory() as tmp:
            order = list(conditions)
            for round_ in range(args.rounds):
                for name in order if round_ % 2 == 0 else reversed(order):
                    out = Path(tmp) / f"{round_}-{name.replace(' ', '_').replace(',', '')}"
                    got = evaluation(args.mode, args.episodes, out, conditions[name])
                    results[name].append(got)
                    print(f"  round {round_ + 1}, {name}: {got['wall']:.1f} s, {got['per_hour']:.0f} episodes/h, "
                          f"{got['succeeded']}/{args.episodes} succeeded", flush=True)
    finally:
        if cluster is not None:
            stop_ray(cluster[0], cluster[2])
    print(f"\nmode {args.mode}, {args.episodes} episodes per condition, {os.cpu_count()} cores; medians of "
          f"{args.rounds} rounds")
    print(f"{'condition':16} {'episodes/h':>10} {'eval wall [s]':>13} {'episode: sim [s]':>16} {'wall [s]':>9} "
          f"{'succeeded':>9}")
    rate = {}
    for name, runs in results.items():
        rate[name] = statistics.median(r["per_hour"] for r in runs)
        print(f"{name:16} {rate[name]:10.0f} {statistics.median(r['wall'] for r in runs):13.1f} "
              f"{statistics.median(r['sim_mean'] for r in runs):16.1f} "
              f"{statistics.median(r['episode_wall'] for r in runs):9.1f} "
              f"{min(r['succeeded'] for r in runs):>6}/{args.episodes}")
    one, many = rate["1 worker"], rate[f"{k} workers"]
    print(f"efficiency of {k} workers: {many / (k * one):.2f} (rate_{k} / ({k} x rate_1); target >= 0.8)")
    if cluster is not None:
        ray_rate = rate[f"Ray, {k} CPUs"]
        nodes = results[f"Ray, {k} CPUs"][0]["nodes"]
        print(f"Ray / local {k} workers: {ray_rate / many:.2f} (target >= 0.9); Ray's nodes: "
              f"{', '.join(n['address'] for n in nodes)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
