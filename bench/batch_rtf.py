"""Real-time factor of a bare batch run (``sigcore run WORLD --transport none``), as a user runs it.

Usage: .venv/bin/python bench/batch_rtf.py [WORLD] [--duration S] [--rounds R] [--smoke]
       --smoke: 1 round of 1 simulated second, to check that the bench runs and prints every figure (tests/bench).

Each round runs the real command twice in a subprocess, alternating, so that machine noise hits both alike:

* bare: ``sigcore run WORLD --transport none --duration S -q`` (nobody drives the robot);
* scripted: the same with ``--controller robot_000=cleanup.robot`` (the clean-up task's Python controller, which
  plans, drives and grasps).

The figure is the real-time factor the command itself prints (simulated seconds per wall second of stepping, start-up
excluded); the medians over the rounds and the range are reported, with the load average of the machine.
"""

from __future__ import annotations

import argparse
import os
import re
import statistics
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
RTF = re.compile(r"real-time factor: ([0-9.]+)")


def rtf(world: str, duration: float, extra: list[str]) -> float:
    """The real-time factor printed by one ``sigcore run`` (exit 0 or 1: the task's verdict does not matter)."""
    cmd = [sys.executable, "-m", "sigcore", "run", world, "--transport", "none", "--duration", str(duration), "-q",
           *extra]
    r = subprocess.run(cmd, capture_output=True, text=True, cwd=ROOT, timeout=600)
    found = RTF.search(r.stdout)
    if r.returncode not in (0, 1) or found is None:
        raise SystemExit(f"{' '.join(cmd)} exited {r.returncode}:\n{r.stdout}\n{r.stderr}")
    return float(found.group(1))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("world", nargs="?", default=str(ROOT / "worlds" / "cleanup.xml"))
    ap.add_argument("--duration", type=float, default=60.0, help="simulated seconds per run [s]")
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--smoke", action="store_true", help="1 round of 1 simulated second: a check that the bench "
                    "runs, not a measurement")
    args = ap.parse_args()
    if args.smoke:
        args.rounds, args.duration = 1, 1.0
    runs: dict[str, list[float]] = {"bare": [], "scripted": []}
    load0 = os.getloadavg()[0]
    for _ in range(args.rounds):
        runs["bare"].append(rtf(args.world, args.duration, []))
        runs["scripted"].append(rtf(args.world, args.duration, ["--controller", "robot_000=cleanup.robot"]))
    print(f"world: {args.world}  {args.rounds} rounds of {args.duration:g} simulated s each, alternating; "
          f"load average {load0:.2f} at the start, {os.getloadavg()[0]:.2f} at the end, {os.cpu_count()} cores")
    for kind, values in runs.items():
        print(f"  {kind:9s} real-time factor median {statistics.median(values):5.1f}  "
              f"(min {min(values):.1f}, max {max(values):.1f})")
    print(f"  scripted / bare: {statistics.median(runs['scripted']) / statistics.median(runs['bare']):.2f}")


if __name__ == "__main__":
    main()
