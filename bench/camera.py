"""Camera rendering: milliseconds per frame through sigcore against MuJoCo's ``Renderer`` alone, and how much of the
rendering overlaps physics.

Usage: .venv/bin/python bench/camera.py [WORLD] [--frames N] [--rounds R] [--seconds S] [--smoke]
       --smoke: 1 round of 2 frames, then 1 round of 0.2 simulated s, to check that the bench runs (tests/bench).

Part 1, per frame (the clean-up world, robot_000's head camera pose): sigcore's renderer (``MujocoRenderer``: the
snapshot of the step, the kinematics of it, the scene, the frustum from the intrinsics, ``mjr_render``, the read-out,
the flip and, for depth, the conversion to metres) against ``mujoco.Renderer`` (``update_scene`` and ``render``, with
``enable_depth_rendering`` for depth) on the same model with the same scene settings (no shadows, no reflections, no
multisampling, the same geom groups), at 320x240 and 640x480, rgb and depth. Rounds alternate the two so that the
machine's noise hits both alike; the ratio is bare / sigcore per round (>= 0.9: sigcore adds at most about 10 %),
and its median over the rounds is reported.

Part 2, overlap: the clean-up world stepped as fast as possible for S simulated seconds three ways, alternating:
physics alone (no one takes images: nothing is rendered); physics with the 320x240 RGB-D head camera at 15 Hz taken
by an observer (rendered on the render thread); and rendering alone (the same number of frames through sigcore's
renderer, no stepping). If rendering did not overlap physics, physics with the camera would take their sum; the
overlap is the share of the shorter one that is hidden: (physics + rendering - both) / min(physics, rendering).
"""

from __future__ import annotations

import argparse
import os
import statistics
import time
from pathlib import Path

os.environ.setdefault("MUJOCO_GL", "egl")

import mujoco  # noqa: E402
import numpy as np  # noqa: E402

from sigcore.backend import CameraView  # noqa: E402
from sigcore.sim import Simulation  # noqa: E402
from sigcore.world import parse_world  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
SIZES = ((320, 240), (640, 480))


def _gl_renderer() -> str:
    """The OpenGL renderer's name (llvmpipe: Mesa in software; else the GPU), from a context of MuJoCo's."""
    backend = os.environ["MUJOCO_GL"]
    if backend == "osmesa":
        from mujoco.osmesa import GLContext
    else:
        from mujoco.egl import GLContext  # type: ignore[no-redef]
    ctx = GLContext(64, 64)
    ctx.make_current()
    from OpenGL import GL

    name = GL.glGetString(GL.GL_RENDERER).decode()
    ctx.free()
    return f"{name} (MUJOCO_GL={backend})"


def _bare(model: mujoco.MjModel, data: mujoco.MjData, view: CameraView, depth: bool):
    """``mujoco.Renderer`` with sigcore's scene settings, a free camera at the view's pose; returns a frame maker."""
    r = mujoco.Renderer(model, view.height, view.width)
    if depth:
        r.enable_depth_rendering()
    cam = mujoco.MjvCamera()
    forward = view.rotation[:, 2]
    cam.type = mujoco.mjtCamera.mjCAMERA_FREE
    cam.distance = 1.0
    cam.lookat[:] = view.position + forward
    cam.azimuth = float(np.degrees(np.arctan2(forward[1], forward[0])))
    cam.elevation = float(np.degrees(np.arcsin(forward[2])))
    option = mujoco.MjvOption()
    option.geomgroup[:] = 0
    option.geomgroup[0] = option.geomgroup[2] = 1

    def frame() -> None:
        r.update_scene(data, cam, option)
        r.scene.flags[mujoco.mjtRndFlag.mjRND_SHADOW] = 0
        r.scene.flags[mujoco.mjtRndFlag.mjRND_REFLECTION] = 0
        r.render()

    return r, frame


def per_frame(sim: Simulation, frames: int, rounds: int) -> None:
    from sigcore_backend_mujoco.render import MujocoRenderer

    sensor = sim.cameras.find("robot_000")
    ours = MujocoRenderer(sim.backend)  # type: ignore[arg-type]
    print(f"{'size':>9} {'kind':>5} {'sigcore ms':>11} {'bare ms':>8} {'bare/sigcore':>13}  (median over {rounds} "
          f"rounds of {frames} frames)")
    for width, height in SIZES:
        base = sensor.view(sim.backend)
        for kind in ("rgb", "depth"):
            view = CameraView(base.position, base.rotation, width, height, (width / 2) / np.tan(np.pi / 6),
                              (width - 1) / 2, (height - 1) / 2, 0.05, 10.0, rgb=kind == "rgb", depth=kind == "depth")
            snap = ours.snapshot()
            ours.render(snap, [view])  # the context and its buffer, made once
            model = ours._model  # the renderer's copy: offsamples 0, the same lights
            data = mujoco.MjData(model)
            data.qpos[:] = sim.backend.data.qpos  # type: ignore[attr-defined]
            mujoco.mj_forward(model, data)
            bare, bare_frame = _bare(model, data, view, kind == "depth")
            bare_frame()
            ratios, mine, theirs = [], [], []
            for _ in range(rounds):
                t0 = time.perf_counter()
                for _ in range(frames):
                    ours.render(ours.snapshot(), [view])
                t1 = time.perf_counter()
                for _ in range(frames):
                    bare_frame()
                t2 = time.perf_counter()
                mine.append((t1 - t0) / frames * 1e3)
                theirs.append((t2 - t1) / frames * 1e3)
                ratios.append(theirs[-1] / mine[-1])
            bare.close()
            print(f"{width}x{height:<4} {kind:>5} {statistics.median(mine):11.1f} {statistics.median(theirs):8.1f} "
                  f"{statistics.median(ratios):13.2f}")
    ours.close()


def overlap(world: Path, seconds: float, rounds: int) -> None:
    from sigcore_backend_mujoco.render import MujocoRenderer

    def physics(camera: bool) -> tuple[float, int]:
        sim = Simulation(parse_world(world), "mujoco")
        frames: list[object] = []
        if camera:
            sim.events.subscribe("camera", frames.append)
        sim.step(100)
        sim.cameras.settle()
        frames.clear()
        steps = round(seconds / sim.dt)
        t0 = time.perf_counter()
        sim.step(steps)
        sim.cameras.settle()
        wall = time.perf_counter() - t0
        sim.cameras.close()
        return wall, len(frames)

    def rendering(n: int) -> float:
        sim = Simulation(parse_world(world), "mujoco")
        sensor = sim.cameras.find("robot_000")
        r = MujocoRenderer(sim.backend)  # type: ignore[arg-type]
        view = sensor.view(sim.backend)
        r.render(r.snapshot(), [view])
        t0 = time.perf_counter()
        for _ in range(n):
            r.render(r.snapshot(), [view])
        wall = time.perf_counter() - t0
        r.close()
        return wall

    alone, both, render, shares = [], [], [], []
    for _ in range(rounds):
        a, _ = physics(False)
        b, n = physics(True)
        c = rendering(n)
        alone.append(a)
        both.append(b)
        render.append(c)
        shares.append((a + c - b) / min(a, c))
    a, b, c = (statistics.median(x) for x in (alone, both, render))
    print(f"\n{seconds:g} simulated s of the clean-up world, as fast as possible; median of {rounds} rounds "
          f"({n} frames of 320x240 RGB-D at 15 Hz):")
    print(f"  physics alone:              {a:6.2f} s wall   real-time factor {seconds / a:5.2f}")
    print(f"  rendering alone:            {c:6.2f} s wall   ({c / n * 1e3:.1f} ms a frame)")
    print(f"  physics + camera:           {b:6.2f} s wall   real-time factor {seconds / b:5.2f}")
    print(f"  if not overlapped (sum):    {a + c:6.2f} s wall   real-time factor {seconds / (a + c):5.2f}")
    print(f"  overlap: {statistics.median(shares):.0%} of the shorter part hidden (per-round median; "
          f"min {min(shares):.0%}, max {max(shares):.0%})")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("world", nargs="?", default=str(ROOT / "worlds" / "cleanup.xml"))
    ap.add_argument("--frames", type=int, default=20, help="frames per round and condition (part 1)")
    ap.add_argument("--rounds", type=int, default=7)
    ap.add_argument("--seconds", type=float, default=10.0, help="simulated seconds per condition (part 2)")
    ap.add_argument("--smoke", action="store_true", help="1 round of 2 frames, then 1 round of 0.2 simulated s: a "
                    "check that the bench runs, not a measurement")
    args = ap.parse_args()
    if args.smoke:
        args.frames, args.rounds, args.seconds = 2, 1, 0.2
    print(f"renderer: {_gl_renderer()}; {os.cpu_count()} CPUs")
    sim = Simulation(parse_world(args.world), "mujoco")
    sim.step(50)
    per_frame(sim, args.frames, args.rounds)
    overlap(Path(args.world), args.seconds, 1 if args.smoke else max(3, args.rounds // 2))


if __name__ == "__main__":
    main()
