"""Reach envelope of the clean-up robot's left arm, measured with the IK solver (the ``_ik_solve`` service).

Usage: .venv/bin/python bench/ik_reach.py [--step S] [--smoke]
       --smoke: a grid step of 0.3 m (--step 0.3), to check that the bench runs and prints every figure (tests/bench).

Targets are points in ``base_link`` (x forward, y left, z up), every ``S`` m (default 0.05) in x and y and every
0.1 m in z (and z 0.79 m: 3 cm above a can on a table), solved with
``move`` false from the zero pose (arms hanging), tolerance 1e-4 m, for two kinds of target:

- ``position``: position only (any hand orientation);
- ``down``: the hand pointing down (quaternion w=1 in ``base_link``: the hand's z axis up, fingers below the grasp
  point, closing along y), what a grasp from above needs.

Prints, per height, the x range reached in the plane of the left shoulder (y = 0.20 m), then the y range reached
at the height of a table-top item, and the tuck pose's hand position. The solver knows joint limits, not
collisions: points in or just above the base (r 0.25 m, top z 0.23 m) count as reached although the arm would hit
the body. The right arm is the mirror image (y -> -y).
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin
from sigcore_ik.chain import set_chain_angles

from sigcore.api.call import call_and_wait
from sigcore.sim import Simulation
from sigcore.world import parse_world

ROOT = Path(__file__).resolve().parent.parent
ROBOT, ARM = "robot_000", "left"
KINDS: dict[str, dict[str, object]] = {"position": {"position_only": True}, "down": {"qw": 1.0}}
TUCK = [0.0, 0.4, 2.4, -2.1, 0.0]
"""The tuck / carry pose of ``worlds/models/sigbot/README.md`` (pan, pitch, elbow, wrist pitch, wrist roll) [rad]."""


def reached(sim: Simulation, entry: Any, x: float, y: float, z: float, kind: str) -> bool:
    """Whether the solver reaches (x, y, z) in base_link with the hand as ``kind`` asks."""
    request = {"x": x, "y": y, "z": z, "frame": "base_link", "chain": ARM, **KINDS[kind]}
    return bool(call_and_wait(sim, entry, ROBOT, request)["success"])


def span(values: list[float]) -> str:
    """``a .. b`` (or ``a .. b, c .. d`` for two runs) of sorted grid values; ``-`` if none."""
    if not values:
        return "-"
    runs, start = [], values[0]
    for prev, cur in zip(values, values[1:], strict=False):
        if cur - prev > 1.5 * (values[1] - values[0] if len(values) > 1 else 1.0):
            runs.append((start, prev))
            start = cur
    runs.append((start, values[-1]))
    return ", ".join(f"{a:.2f} .. {b:.2f}" for a, b in runs)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--step", type=float, default=0.05, help="grid step [m]")
    parser.add_argument("--smoke", action="store_true", help="a grid step of 0.3 m: a check that the bench runs, "
                        "not a measurement")
    args = parser.parse_args()
    if args.smoke:
        args.step = 0.3
    sim = Simulation(parse_world(ROOT / "worlds" / "cleanup.xml"), "mujoco")
    entry = next(e for e in sim.api_entries() if e.suffix == "_ik_solve")
    step = args.step
    xs = [round(v, 3) for v in np.arange(0.0, 1.2 + 1e-9, step)]
    ys = [round(v, 3) for v in np.arange(-0.6, 1.0 + 1e-9, step)]
    zs = sorted([round(v, 3) for v in np.arange(0.2, 1.9 + 1e-9, 0.1)] + [0.79])
    print(f"x range reached at y = 0.20 m (left shoulder plane), x grid {step} m, base_link [m]")
    print("| z | position only | hand pointing down |\n|---|---|---|")
    for z in zs:
        row = {k: [x for x in xs if reached(sim, entry, x, 0.2, z, k)] for k in KINDS}
        print(f"| {z:.2f} | {span(row['position'])} | {span(row['down'])} |")
    for z, x in ((0.79, 0.5), (0.45, 0.5)):
        row = {k: [y for y in ys if reached(sim, entry, x, y, z, k)] for k in KINDS}
        print(f"y range reached at x = {x} m, z = {z} m: position only {span(row['position'])}; "
              f"hand down {span(row['down'])}")
    ik = sim.features["ik"]
    robot = ik.robot(ROBOT)  # type: ignore[attr-defined]
    chain = robot.chain(ARM)
    q = set_chain_angles(robot.model, chain, pin.neutral(robot.model.model), np.array(TUCK))
    pin.framesForwardKinematics(robot.model.model, robot.model.data, q)
    tip = robot.model.data.oMf[chain.tip_frame]
    print(f"tuck {TUCK}: hand at {np.round(tip.translation, 3).tolist()} in base_link, hand z axis "
          f"{np.round(tip.rotation[:, 2], 3).tolist()}")


if __name__ == "__main__":
    main()
