"""Every bench in ``bench/`` runs in its smoke mode (``--smoke``: the smallest sizes that still print every figure) as
a person runs it, a script in a process of its own, and prints each of its figures: a bench that no longer runs, or no
longer reports what ``docs/benchmarks.md`` quotes, fails here (issue 29, "No bench rots"). Figures are checked by
their labels and table headers, with a number where the figure is one, never by their values: a smoke run measures
nothing."""

from __future__ import annotations

import os
import re
import shutil
import signal
import subprocess
import sys
from pathlib import Path

import pytest

pytestmark = pytest.mark.slow

ROOT = Path(__file__).resolve().parents[2]
BENCH = ROOT / "bench"
TIMEOUT = 300.0
"""Longest a smoke run may take [s]: 1-30 s each on the project's 2 cores with a test suite running beside it, but
100 s for ``viewer_overhead`` (two browsers pinned to one CPU) at a load average of 15."""

N = r"-?\d+(\.\d+)?"
"""A number as the benches print them."""


def lit(text: str) -> str:
    """A pattern for ``text`` as it is."""
    return re.escape(text)


def row(*cells: str) -> str:
    """A pattern for a Markdown table row that starts with these cells (patterns)."""
    return r"^\| " + r" \| ".join(cells) + r" \|"


# ------------------------------------------------------------------------------------- what each bench must print
FIGURES: dict[str, list[str]] = {
    "backend_differences": [row(r"figure", r"\w+", r"\w+")] + [row(lit(label), ".+", ".+") for label in (
        "drop 1 m: first contact - sqrt(2h/g)", "straight 2 s at 0.5 m/s: distance error",
        "straight: sideways drift, heading", "turn in place 1 s at 1 rad/s: heading error",
        "turn in place: centre drift", "arc 2 s (3 and 5 rad/s): end position error",
        "servo holding a horizontal arm: sag", "servo step 0 -> 0.8 rad: time to 95 %",
        "lidar in room (360 rays): max range error", "ray_cast of 360 rays, excluding own robot",
        "box, CoM 5 cm off-centre, dropped 0.5 m: tilt at rest", "cylinder (r 5 cm, 30 cm) dropped 1 m: rests at z",
        "step of the bot world", "reset (nothing changed)", "reset after a collision-mode change")],
    "batch_rtf": [rf"^  bare +real-time factor median +{N}", rf"^  scripted +real-time factor median +{N}",
                  rf"^  scripted / bare: {N}"],
    "camera": [r"^renderer: ", r"size +kind +sigcore ms +bare ms +bare/sigcore"]
    + [rf"^{size} +{kind} +{N} +{N} +{N}$" for size in ("320x240", "640x480") for kind in ("rgb", "depth")]
    + [rf"^  {lit(label)} +{N} s wall" for label in ("physics alone:", "rendering alone:", "physics + camera:",
                                                     "if not overlapped (sum):")]
    + [r"^  overlap: -?\d+% of the shorter part hidden"],
    "eval_scaling": [r"condition +episodes/h +eval wall \[s\] +episode: sim \[s\] +wall \[s\] +succeeded",
                     rf"^1 worker +{N} +{N} +{N} +{N} +\d+/\d+$", rf"^\d+ workers +{N} +{N} +{N} +{N} +\d+/\d+$",
                     rf"^Ray, \d+ CPUs +{N} +{N} +{N} +{N} +\d+/\d+$", rf"^efficiency of \d+ workers: {N}",
                     rf"^Ray / local \d+ workers: {N} .*Ray's nodes: \S+"],
    "ik": [r"^arm +target +success +median +p99 +max +cpu med +cpu p99 +err med +err max +iter$"]
    + [rf"^{arm} +{kind} +{N}% +{N}ms" for arm in ("robot_000/left_arm", "robot_000/right_arm", "arm_0/arm")
       for kind in ("pose", "position")]
    + [r"^moves: \d+ full-pose targets per arm"]
    + [rf"^{arm} +success {N}% +final error median {N} mm, max {N} mm; move median {N} s simulated"
       for arm in ("robot_000/left_arm", "robot_000/right_arm", "arm_0/arm")],
    "ik_reach": [r"^x range reached at y = 0\.20 m", row("z", "position only", "hand pointing down"),
                 row(lit("0.79"), ".+", ".+"),
                 r"^y range reached at x = 0\.5 m, z = 0\.79 m: position only .+; hand down ",
                 r"^y range reached at x = 0\.5 m, z = 0\.45 m: position only .+; hand down ",
                 r"^tuck \[.+\]: hand at \[.+\] in base_link"],
    "other_core_load": [r"^simulation on CPU 0, \d+ rounds x \d+ steps"]
    + [rf"^  {load} +{N} steps/s +ratio to quiet {N}" for load in ("quiet", "memory", "compute")],
    "rclpy_calls": [rf"^{way} +{N} ms wall +{N} ms CPU per call" for way in ("global", "own")]
    + [rf"^global / own: {N}x wall, {N}x CPU"],
    "record_overhead": [rf"^{t} +{what}: plain +{N} steps/s, recording +{N} steps/s; ratio {N} \(per round: median {N}"
                        for t in ("ros2", "none") for what in ("wall", "CPU ")]
    + [rf"^{t} +recorded \d+ messages in \d+ steps, {N} MB \({N} kB per simulated second\)" for t in ("ros2", "none")],
    "ros2_discovery": [r"^sigros_agents +topics +services +all seen \[s\] +first answer \[s\]$",
                       rf"^all +\d+ +\d+ +{N} +{N}$", rf"^robots agents +\d+ +\d+ +{N} +{N}$"],
    "ros2_overhead": [r"endpoints: \d+", r"^ with no subscriber:$",
                      r"^ with a subscriber process on /clock, /tf, odom, joint_states, scan:$",
                      rf"^  raw mj_step +{N} steps/s", rf"^  sigcore \+ ROS 2 transport +{N} steps/s",
                      rf"^  ratio \(target >= 0\.6\): wall {N} +simulation-thread cpu {N}",
                      rf"^  ratio \(target >= 0\.5\): wall {N} +simulation-thread cpu {N}",
                      r"^  messages received by the subscriber: \{'clock': \d+",
                      r"^round trip of /robot_000_get_obj_position vs a bare rclpy service",
                      rf"^  sigcore +median +{N} ms +p99 +{N} ms", rf"^  bare +median +{N} ms +p99 +{N} ms",
                      rf"^  ratio +median {N} +p99 {N}"],
    "sim_throughput": [rf"^  {lit(label)} +{N} steps/s +{N} us/step +real-time factor +{N}" for label in (
        "raw mj_step", "raw mj_step + mj_multiRay lidar", "sigcore step (all on)", "sigcore step, no lidar")]
    + [rf"^{lit(label)} +{N}" for label in ("ratio sigcore / (raw + same lidar):", "ratio sigcore without lidar / raw:",
                                            "ratio sigcore (all on) / bare mj_step:")],
    "step_breakdown": [r"^variant +us/step +added +alone$", rf"^mj_step +{N}$"]
    + [rf"^{lit(label)} +{N} +[+-]{N} +{N}$" for label in ("backend", "+ contacts", "+ step channel", "+ lidar")]
    + [rf"^Simulation\.step +{N}$",
       rf"^Simulation\.step - mj_step: {N} us a step \(of which the parts alone: {N} us\)"],
    "sim_throughput_bullet": [rf"^  {lit(label)} +{N} steps/s +{N} us/step +real-time factor +{N}" for label in (
        "raw stepSimulation", "raw stepSimulation + rayTestBatch lidar", "sigcore step (all on)",
        "sigcore step, no lidar", "sigcore step, no lidar, no features")]
    + [rf"^  {lit(label)} +{N} +\({N}\)" for label in (
        "sigcore / (raw + same lidar):", "sigcore without lidar / raw:", "sigcore (all on) / bare stepSimulation:",
        "sigcore without lidar, features / raw:")],
    "slam_accuracy": [rf"^route +\d+ loops, {N} m, {N} s simulated, \d+ scans"]
    + [rf"^{lit(label)} +{N}" for label in (
        "ATE RMSE [m]", "max position error [m]", "yaw RMSE [rad]", "final drift [m]", "scans over 100 ms",
        "real-time factor", "map IoU (occupied, observed cells)", "map IoU, 1-cell tolerance")]
    + [rf"^{lit(label)} +median {N}, p99 {N}, max {N}" for label in ("per-scan time [ms]",
                                                                      "per-scan CPU time [ms]")]
    + [r"^configuration +voxel_size=", r"^cells occupied: SLAM / truth \(observed\) +\d+ / \d+"],
    "spawn": [r"^backend +build ms +spawn1 ms +spawn10 ms +delete1 ms +churned st/s +fresh st/s +ratio$"]
    + [rf"^{backend} +{N} +{N} +{N} +{N} +{N} +{N} +{N}$" for backend in ("mujoco", "bullet")]
    + [rf"^mujoco clean-up step: sparse Jacobian {N} us, automatic {N} us, ratio {N}"],
    "startup": [row(lit("N"), lit("none [s]"), lit("ros2 [s]"), "ROS 2 endpoints"), row("30", N, N, r"\d+")],
    "viewer_first_paint": [r"^initial scene: \d+ messages, \d+ KiB on the wire",
                           rf"^load 1: load_event {N} s, panel {N} s, scene {N} s, useful {N} s"]
    + [rf"^{key}: median {N} s" for key in ("load_event", "panel", "scene", "useful")],
    "viewer_handover": [rf"^round 1: direct {N} ms, handed {N} ms per push, ratio {N}",
                        r"^\d+ frames, \d+ pushes x \d+ rounds", rf"^median per push: direct {N} ms, handed {N} ms",
                        rf"^handed / direct: median {N}"],
    "viewer_overhead": [r"^world: .+ viewers at \d+ Hz", r"^browsers: headless Chromium", r"^pinning: ",
                        r"^rounds: \d+ x \d+ steps per condition"]
    + [rf"^  {lit(label)} +{N} steps/s" for label in (
        "no viewer (browsers frozen)", "no viewer again (a second simulation)",
        "no viewer, browser F drawing another run", "viewer A, browser A connected")]
    + [rf"^ratio {lit(c)} / none: +{N}" for c in ("again", "drawing", "viewer")]
    + [rf"^ratio viewer / drawing: {N}", r"^median of the per-round ratios",
       rf"^  viewer / none: +{N} \({N}-{N}\)", r"^CPU while each condition ran",
       rf"^  viewer +\d+ updates \({N}/s\); on the simulation thread viewer.service {N} ms per update",
       r"^  real-time phase \(\d+ steps in", r"^latency \[ms\] from the snapshot taken on the simulation thread",
       r"^  viewer A, browser A connected, as fast as possible \(\d+ updates pushed",
       r"^  viewer A, real time \(\d+ updates pushed, \d+ seen in the page\):"]
    + [rf"^    {lit(label)} +median +{N} +p90" for label in (
        "handed to viser (viewer's process)", "shown in the page's DOM", "next animation frame after")],
    "worlds": [row("backend", lit("build clean-up from scratch (parse + Simulation)"), "parse alone",
                   "load_world of it while running", lit("steps/s after 20 loads"), "fresh", "ratio")]
    + [row(backend, f"{N} ms", f"{N} ms", f"{N} ms", N, N, N) for backend in ("mujoco", "bullet")],
}
"""Per bench (``bench/NAME.py``), patterns (``re.MULTILINE``) that its ``--smoke`` output must each match."""

ROS2 = {"eval_scaling", "rclpy_calls", "record_overhead", "ros2_discovery", "ros2_overhead", "startup"}
"""The benches that start ROS 2 nodes. They run one after the other (one ``xdist_group``): each picks a
``ROS_DOMAIN_ID`` of 101-119 or 150-219 by itself, away from the tests' but not from another bench's."""
BROWSER = {"viewer_first_paint", "viewer_overhead"}
"""The benches that drive a headless browser."""
PINNED = {"other_core_load", "viewer_overhead"}
"""The benches that pin processes to CPUs 0 and 1."""


def _case(name: str) -> object:
    """Bench ``name`` as a test case, marked ``ros2`` (and in the ROS 2 benches' group) and ``browser`` by what it
    starts."""
    marks = []
    if name in ROS2:
        marks += [pytest.mark.ros2, pytest.mark.xdist_group("bench_ros2")]
    if name in BROWSER:
        marks.append(pytest.mark.browser)
    return pytest.param(name, marks=marks, id=name)


def _unmet(name: str) -> str | None:
    """Why bench ``name`` cannot run on this machine (a reason to skip), or None. (Without rclpy the ROS 2 benches,
    marked ``ros2``, are skipped by tests/tiers.py.)

    Raises:
        RuntimeError: the bench drives a browser and Chromium, its driver or selenium is missing: a failed set-up, as
            for the viewer's browser tests (``SIGCORE_NO_BROWSER`` skips them).
    """
    if name == "eval_scaling" and shutil.which("ray", path=str(Path(sys.executable).parent)) is None:
        return "Ray is not installed (scripts/setup.sh installs it)"
    if name in PINNED and not {0, 1} <= os.sched_getaffinity(0):
        return f"the bench pins to CPUs 0 and 1; this process may run on {sorted(os.sched_getaffinity(0))}"
    if name in BROWSER:
        if os.environ.get("SIGCORE_NO_BROWSER"):
            return "SIGCORE_NO_BROWSER is set: the viewer's browser tests are skipped"
        from sigcore_viewer.browser import missing

        if missing() is not None:  # scripts/setup.sh installs them as root: a missing browser is a failed set-up
            raise RuntimeError(f"the viewer's browser tests cannot run: {missing()}")
    return None


def _smoke(name: str) -> tuple[int, str, str]:
    """Run ``bench/NAME.py --smoke`` from the repository's root: (exit code, stdout, stderr). Each ROS 2 bench picks
    its own ``ROS_DOMAIN_ID`` (out of the tests' 1-96) when none is set, so none is passed on. A run still going
    after :data:`TIMEOUT` is interrupted (its process group; SIGKILL 30 s later) and fails the test."""
    env = {k: v for k, v in os.environ.items() if k != "ROS_DOMAIN_ID"}
    proc = subprocess.Popen([sys.executable, str(BENCH / f"{name}.py"), "--smoke"], cwd=ROOT, env=env, text=True,
                            stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            start_new_session=True)
    try:
        out, err = proc.communicate(timeout=TIMEOUT)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGINT)  # the benches clean up their processes on KeyboardInterrupt
        try:
            out, err = proc.communicate(timeout=30)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
            out, err = proc.communicate()
        pytest.fail(f"bench/{name}.py --smoke still ran after {TIMEOUT:g} s:\n{out[-3000:]}\n{err[-3000:]}")
    return proc.returncode, out, err


def test_every_bench_has_a_smoke_check() -> None:
    """Every ``bench/*.py`` has its figures listed here and every listed bench exists: a bench cannot be added
    without a smoke check."""
    assert sorted(p.stem for p in BENCH.glob("*.py")) == sorted(FIGURES)


@pytest.mark.parametrize("name", [_case(name) for name in sorted(FIGURES)])
def test_the_bench_runs_in_smoke_mode_and_prints_every_figure(name: str) -> None:
    """``bench/NAME.py --smoke`` exits 0 and its output has every figure the bench reports."""
    reason = _unmet(name)
    if reason is not None:
        pytest.skip(reason)
    code, out, err = _smoke(name)
    assert code == 0, f"bench/{name}.py --smoke exited {code}:\n{out[-3000:]}\n{err[-3000:]}"
    missing = [pattern for pattern in FIGURES[name] if re.search(pattern, out, re.MULTILINE) is None]
    assert not missing, f"bench/{name}.py --smoke did not print {missing}:\n{out[-5000:]}"
