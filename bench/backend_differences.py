"""Figures of the differences between physics backends that the conformance suite (tests/backends) exposes.

Usage: .venv/bin/python bench/backend_differences.py [--backends mujoco bullet] [--smoke]
       --smoke: the costs timed over 2 ray casts and 100 steps, to check that the bench runs (tests/bench).

Runs the same small scenarios as the suite on every registered backend (or the ones named) and prints, per
backend: drop time error, straight-drive and turn-in-place errors against the kinematic prediction, arc error,
position-servo sag under gravity, lidar range error in a closed room, whether a box with an off-centre centre
of mass dropped from 0.5 m lands flat, the cost of reset and of one step of the bot world.
"""

from __future__ import annotations

import argparse
import math
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from sigcore import plugins
from sigcore.backend import Backend
from sigcore.geometry import quat_yaw
from sigcore.world import World, parse_world

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tests" / "backends"))
from conformance_worlds import BOT_URDF, G, robot  # noqa: E402
from test_conformance_sensing import ROOM, _room_distance  # noqa: E402
from test_conformance_state import BIN_URDF  # noqa: E402

DT = 0.002


def _world(tmp: Path, body: str) -> World:
    (tmp / "bot.urdf").write_text(BOT_URDF)
    (tmp / "bin.urdf").write_text(BIN_URDF)
    path = tmp / "w.xml"
    path.write_text(f'<world name="w" timestep="{DT}">\n{body}\n</world>\n')
    return parse_world(path)


def _run(b: Backend, seconds: float) -> None:
    for _ in range(round(seconds / DT)):
        b.step()


def figures(name: str, tmp: Path, casts: int, steps: int) -> dict[str, str]:
    """The figures of backend ``name``; the costs are the means over ``casts`` ray casts and ``steps`` steps."""
    cls = plugins.get_backend(name)

    def build(body: str) -> Backend:
        b = cls()
        b.build(_world(tmp, body))
        return b

    out: dict[str, str] = {}
    b = build('<object name="box" shape="box" size="0.1 0.1 0.1" pose="0 0 1.05"/>')
    steps = 0
    while not b.contacts():
        b.step()
        steps += 1
    out["drop 1 m: first contact - sqrt(2h/g)"] = f"{(steps * DT - math.sqrt(2 / G)) * 1e3:+.1f} ms"

    b = build(robot())
    for j in ("wheel_l_joint", "wheel_r_joint"):
        b.set_joint_velocity("bot", j, 5.0, 20.0)
    _run(b, 0.5)
    p0 = b.get_pose("bot")[0]
    _run(b, 2.0)
    p, q = b.get_pose("bot")
    out["straight 2 s at 0.5 m/s: distance error"] = f"{(p[0] - p0[0] - 1.0) * 1e3:+.2f} mm"
    out["straight: sideways drift, heading"] = f"{(p[1] - p0[1]) * 1e3:+.2f} mm, {quat_yaw(q) * 1e3:+.2f} mrad"

    b = build(robot())
    b.set_joint_velocity("bot", "wheel_l_joint", -2.0, 20.0)
    b.set_joint_velocity("bot", "wheel_r_joint", 2.0, 20.0)
    _run(b, 0.5)
    y0 = quat_yaw(b.get_pose("bot")[1])
    _run(b, 1.0)
    p, q = b.get_pose("bot")
    out["turn in place 1 s at 1 rad/s: heading error"] = f"{(quat_yaw(q) - y0 - 1.0) / 1.0 * 100:+.2f} %"
    out["turn in place: centre drift"] = f"{np.linalg.norm(p[:2]) * 1e3:.1f} mm"

    b = build(robot())
    b.set_joint_velocity("bot", "wheel_l_joint", 3.0, 20.0)
    b.set_joint_velocity("bot", "wheel_r_joint", 5.0, 20.0)
    _run(b, 0.5)
    p0, q0 = b.get_pose("bot")
    yaw0 = quat_yaw(q0)
    _run(b, 2.0)
    p, q = b.get_pose("bot")
    v, w = 0.1 * 4.0, 0.1 * 2.0 / 0.4
    yaw1 = yaw0 + 2.0 * w
    exp = p0[:2] + v / w * np.array([math.sin(yaw1) - math.sin(yaw0), math.cos(yaw0) - math.cos(yaw1)])
    out["arc 2 s (3 and 5 rad/s): end position error"] = f"{np.linalg.norm(p[:2] - exp) * 1e3:.1f} mm"

    b = build(robot(extra=' fixed="true"'))
    b.set_joint_angle("bot", "shoulder", math.pi / 2)
    _run(b, 1.0)
    sag = b.get_joint_angle("bot", "shoulder") - math.pi / 2
    out["servo holding a horizontal arm: sag"] = f"{sag * 1e3:+.2f} mrad"
    b = build(robot(extra=' fixed="true"'))
    b.set_joint_target("bot", "shoulder", 0.8)
    t = 0
    while abs(b.get_joint_angle("bot", "shoulder") - 0.8) > 0.8 * 0.05 and t < 2000:
        b.step()
        t += 1
    out["servo step 0 -> 0.8 rad: time to 95 %"] = f"{t * DT * 1e3:.0f} ms"

    b = build(ROOM + robot(pose=f"0.3 -0.2 0 0 0 {math.radians(30)}"))
    origin = b.get_pose("bot", "lidar_link")[0]
    ang = np.linspace(-math.pi, math.pi, 360, endpoint=False) + 0.0123
    dirs = np.stack([np.cos(ang), np.sin(ang), np.zeros(360)], axis=1)
    exp_r = np.array([_room_distance(origin, d) for d in dirs])
    t0 = time.perf_counter()
    for _ in range(casts):
        dist = b.ray_cast(origin, dirs, 10.0, exclude="bot")
    cost = (time.perf_counter() - t0) / casts
    out["lidar in room (360 rays): max range error"] = f"{np.abs(dist - exp_r).max() * 1e3:.4f} mm"
    out["ray_cast of 360 rays, excluding own robot"] = f"{cost * 1e6:.0f} us"

    b = build('<object name="d" urdf="bin.urdf" pose="2 0 0.5"/>')
    _run(b, 1.0)
    w_, x_, y_, _z = b.get_pose("d")[1]
    tilt = math.degrees(2 * math.asin(min(1.0, math.hypot(x_, y_))))
    out["box, CoM 5 cm off-centre, dropped 0.5 m: tilt at rest"] = f"{tilt:.1f} deg"
    b = build('<object name="cy" shape="cylinder" size="0.05 0.3" pose="2 0 1"/>')
    _run(b, 1.5)
    out["cylinder (r 5 cm, 30 cm) dropped 1 m: rests at z"] = f"{b.get_pose('cy')[0][2]:.3f} m (upright 0.150)"

    b = build(robot() + '<object name="o" shape="box" size="0.2 0.2 0.2" pose="0 1 0.1"/>')
    t0 = time.perf_counter()
    for _ in range(steps):
        b.step()
    out["step of the bot world"] = f"{(time.perf_counter() - t0) / steps * 1e6:.1f} us"
    t0 = time.perf_counter()
    b.reset()
    out["reset (nothing changed)"] = f"{(time.perf_counter() - t0) * 1e3:.2f} ms"
    b.set_collision_mode("o", False)
    t0 = time.perf_counter()
    b.reset()
    out["reset after a collision-mode change"] = f"{(time.perf_counter() - t0) * 1e3:.2f} ms"
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--backends", nargs="*", default=sorted(plugins.backends()))
    ap.add_argument("--smoke", action="store_true", help="the costs over 2 ray casts and 100 steps: a check that "
                    "the bench runs, not a measurement")
    args = ap.parse_args()
    casts, steps = (2, 100) if args.smoke else (20, 2000)
    results = {}
    for name in args.backends:
        with tempfile.TemporaryDirectory() as tmp:
            results[name] = figures(name, Path(tmp), casts, steps)
    keys = list(next(iter(results.values())))
    print(f"| figure | {' | '.join(args.backends)} |")
    print(f"|---|{'---|' * len(args.backends)}")
    for k in keys:
        print(f"| {k} | {' | '.join(results[n][k] for n in args.backends)} |")


if __name__ == "__main__":
    main()
