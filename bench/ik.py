"""IK bench: random reachable in-limit targets for each arm of robot_000 (clean-up world) and for arm_0 (arm6 world).

Usage: .venv/bin/python bench/ik.py [--targets N] [--moves M] [--seed S] [--smoke]
       --smoke: 10 targets and 1 move per arm, to check that the bench runs and prints every figure (tests/bench).

For each arm and for full-pose and position-only targets: N targets, each the tip pose of a random in-limit
configuration, solved from the previous target's configuration (a random, far start: what a robot sees when it is
sent from one random target to the next). Reports the success rate, the solve time (median, p99; the solver call
alone, in this process) and the solver's position error, checked by forward kinematics of the solution.

Then M full-pose targets per arm are sent through the ``_ik_solve`` service with ``move`` true: the arm travels
there through its joint servos (MuJoCo, the world's ``<gains>``), and the tip's position error measured in the
simulation after it has settled is reported. arm6 targets whose joint-space path would take a link below 0.05 m
(into the ground) are skipped.

Solve times are given as wall-clock and as CPU time of this process (``time.thread_time``): on a shared machine
the wall-clock p99 includes time the process was not running; the load average is printed.
"""

from __future__ import annotations

import argparse
import gc
import os
import statistics
import time
from pathlib import Path

import numpy as np
import pinocchio as pin
from sigcore_ik.chain import Chain, set_chain_angles, tip_pose
from sigcore_ik.feature import IkFeature
from sigcore_ik.model import RobotModel
from sigcore_ik.solver import solve

from sigcore.api.call import call_and_wait
from sigcore.sim import Simulation
from sigcore.world import parse_world

ROOT = Path(__file__).resolve().parent.parent
ARMS = [("cleanup.xml", "robot_000", "left_arm"), ("cleanup.xml", "robot_000", "right_arm"),
        ("arm6.xml", "arm_0", "arm")]


def _percentile(values: list[float], p: float) -> float:
    return float(np.percentile(np.asarray(values), p))


def bench_solver(model: RobotModel, chain: Chain, q0: np.ndarray, position_only: bool, n: int,
                 rng: np.random.Generator) -> dict[str, float]:
    """Solve ``n`` random targets, each from the previous one's configuration."""
    times, cpu, errors, iterations, ok = [], [], [], [], 0
    start = q0.copy()
    gc.disable()
    try:
        for _ in range(n):
            goal = rng.uniform(chain.lower, chain.upper)
            target = tip_pose(model, chain, set_chain_angles(model, chain, q0, goal))
            t0, c0 = time.perf_counter(), time.thread_time()
            result = solve(model, chain, start, target, position_only, 1e-4)
            times.append(time.perf_counter() - t0)
            cpu.append(time.thread_time() - c0)
            reached = tip_pose(model, chain, set_chain_angles(model, chain, q0, result.angles))
            error = float(np.linalg.norm(reached.translation - target.translation))
            rot = float(np.linalg.norm(pin.log3(reached.rotation.T @ target.rotation)))
            in_limits = bool(np.all(result.angles >= chain.lower) and np.all(result.angles <= chain.upper))
            ok += result.success and in_limits and error <= 1e-4 and (position_only or rot <= 1e-3)
            errors.append(error)
            iterations.append(result.iterations)
            start = set_chain_angles(model, chain, q0, goal)
    finally:
        gc.enable()
    return {"success": ok / n, "median_ms": 1e3 * statistics.median(times), "p99_ms": 1e3 * _percentile(times, 99),
            "max_ms": 1e3 * max(times), "cpu_median_ms": 1e3 * statistics.median(cpu),
            "cpu_p99_ms": 1e3 * _percentile(cpu, 99), "error_median": statistics.median(errors),
            "error_max": max(errors), "iterations_median": statistics.median(iterations)}


def _clear_of_ground(model: RobotModel, chain: Chain, q0: np.ndarray, a: np.ndarray, b: np.ndarray) -> bool:
    """Every link from the forearm on stays above 0.05 m along the straight joint-space path a -> b (the links'
    cylinders are at most 0.054 m in radius)."""
    frames = [model.frame_id(link) for link in model.links][3:]
    for s in np.linspace(0.0, 1.0, 21):
        pin.framesForwardKinematics(model.model, model.data, set_chain_angles(model, chain, q0, a + s * (b - a)))
        if min(model.data.oMf[f].translation[2] for f in frames) < 0.05:
            return False
    return True


def bench_moves(world_file: str, robot: str, chain_name: str, m: int, rng: np.random.Generator) -> dict[str, float]:
    """``m`` full-pose targets through ``_ik_solve`` with ``move`` true; errors measured in the simulation."""
    sim = Simulation(parse_world(ROOT / "worlds" / world_file), "mujoco")
    feature = sim.features["ik"]
    assert isinstance(feature, IkFeature)
    r = feature.robots[robot]
    chain = r.chain(chain_name)
    entry = next(e for e in sim.api_entries() if e.suffix == "_ik_solve")
    sim.step(10)
    finals: list[float] = []
    durations: list[float] = []
    ok = skipped = 0
    while len(finals) < m:
        if skipped > 100 * m:
            raise RuntimeError(f"no collision-free target found for {robot}/{chain_name} in {skipped} tries")
        q = r.configuration()
        current = np.array([r.model.angle(q, j) for j in chain.joints])
        goal = rng.uniform(chain.lower, chain.upper)
        if robot == "arm_0" and not _clear_of_ground(r.model, chain, q, current, goal):
            skipped += 1
            continue
        target = r.base_pose() * tip_pose(r.model, chain, set_chain_angles(r.model, chain, q, goal))
        quat = pin.Quaternion(target.rotation)
        t0 = sim.time
        res = call_and_wait(sim, entry, robot, {
            "x": target.translation[0], "y": target.translation[1], "z": target.translation[2],
            "qw": quat.w, "qx": quat.x, "qy": quat.y, "qz": quat.z, "chain": chain.name, "move": True})
        durations.append(sim.time - t0)
        ok += bool(res["success"]) and res["final_error"] <= 5e-3
        finals.append(res["final_error"] if res["success"] else float("nan"))
        if not res["success"]:
            print(f"    move failed: {res['message']}")
    gains = sim.entities.robot_model(robot).gains
    return {"success": ok / m, "final_median_mm": 1e3 * float(np.nanmedian(finals)),
            "final_max_mm": 1e3 * float(np.nanmax(finals)), "duration_median_s": statistics.median(durations),
            "skipped": skipped, "kp": gains.kp, "kv": gains.kv, "max_torque": gains.max_torque}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--targets", type=int, default=500, help="solver targets per arm and target kind (>= 200)")
    ap.add_argument("--moves", type=int, default=20, help="simulated moves per arm")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--smoke", action="store_true", help="10 targets and 1 move per arm: a check that the bench "
                    "runs, not a measurement")
    args = ap.parse_args()
    if args.smoke:
        args.targets, args.moves = 10, 1
    rng = np.random.default_rng(args.seed)
    print(f"solver: {args.targets} random reachable in-limit targets per arm, each solved from the previous "
          "target's configuration; tolerance 1e-4 m (and 1e-3 rad for full poses)")
    print(f"load average: {' '.join(f'{x:.2f}' for x in os.getloadavg())} on {os.cpu_count()} CPUs")
    print(f"{'arm':<22} {'target':<9} {'success':>8} {'median':>9} {'p99':>9} {'max':>9} {'cpu med':>9} "
          f"{'cpu p99':>9} {'err med':>10} {'err max':>10} {'iter':>5}")
    for world_file, robot, chain_name in ARMS:
        sim = Simulation(parse_world(ROOT / "worlds" / world_file), "mujoco")
        r = sim.features["ik"].robots[robot]  # type: ignore[attr-defined]
        chain = r.chain(chain_name)
        q0 = r.configuration()
        for position_only in (False, True):
            s = bench_solver(r.model, chain, q0, position_only, args.targets, rng)
            kind = "position" if position_only else "pose"
            print(f"{robot + '/' + chain_name:<22} {kind:<9} {100 * s['success']:>7.1f}% {s['median_ms']:>7.3f}ms "
                  f"{s['p99_ms']:>7.3f}ms {s['max_ms']:>7.2f}ms {s['cpu_median_ms']:>7.3f}ms {s['cpu_p99_ms']:>7.3f}ms "
                  f"{s['error_median']:>9.2e}m {s['error_max']:>9.2e}m "
                  f"{s['iterations_median']:>5.0f}")
    print(f"\nmoves: {args.moves} full-pose targets per arm through _ik_solve (move true), MuJoCo, error of the tip "
          "measured in the simulation after the arm settled")
    for world_file, robot, chain_name in ARMS:
        s = bench_moves(world_file, robot, chain_name, args.moves, rng)
        print(f"{robot + '/' + chain_name:<22} success {100 * s['success']:.0f}%  final error median "
              f"{s['final_median_mm']:.3f} mm, max {s['final_max_mm']:.3f} mm; move median {s['duration_median_s']:.2f}"
              f" s simulated; gains kp {s['kp']:g} N m/rad, kv {s['kv']:g} N m s/rad, max_torque {s['max_torque']:g}"
              f" N m{'; skipped ' + str(s['skipped']) + ' (path into the ground)' if s['skipped'] else ''}")


if __name__ == "__main__":
    main()
