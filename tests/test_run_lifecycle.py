"""A run's lifecycle: SIGINT and SIGTERM end a ROS 2 run with its results, the default transport and pace, the world
events fired by the simulation itself, and one error root for the core and the bundled plugins."""

from __future__ import annotations

import importlib
import importlib.util
import inspect
import json
import os
import pkgutil
import re
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from types import ModuleType

import pytest
import trackers
from rosdomains import next_domain

import sigcore
from sigcore import SigcoreError, hookimpl, plugins
from sigcore.sim import Simulation, run
from sigcore.world import World

ROOT = Path(__file__).parent.parent
CLEANUP = ROOT / "worlds" / "cleanup.xml"
WORLD = ROOT / "tests" / "data" / "sim" / "world.xml"
CLIENTS = ROOT / "tests" / "ros2" / "clients"
STARTUP = 90.0
"""Wall seconds a simulation process may take to build the world and start ROS 2 (about 2 s alone)."""
needs_ros = pytest.mark.ros2  # skipped where rclpy cannot be imported (tests/conftest.py)


def ros_env() -> dict[str, str]:
    """A private ROS domain for this test process, discovery on this machine only, unbuffered output."""
    env = dict(os.environ)
    env["ROS_DOMAIN_ID"] = str(next_domain())
    env["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
    env["PYTHONUNBUFFERED"] = "1"
    env.pop("ROS_STATIC_PEERS", None)
    return env


def _ignore_sigint() -> None:
    """In the child before exec: SIGINT ignored, as a shell leaves it for a job started in the background."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)


def _block_sigint() -> None:
    """In the child before exec: SIGINT blocked, as a parent whose starting thread blocked it leaves it."""
    signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})


STARTS = {"default": None, "ignored": _ignore_sigint, "blocked": _block_sigint}
"""How SIGINT is left to a child process by the one starting it."""


class Proc:
    """A process in its own session whose merged output is read by a thread, line by line."""

    def __init__(self, args: list[str], env: dict[str, str], sigint: str = "default") -> None:
        self.lines: list[str] = []
        self._new_line = threading.Condition()
        self.proc = subprocess.Popen(args, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                                     start_new_session=True, preexec_fn=STARTS[sigint])
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()

    def _read(self) -> None:
        assert self.proc.stdout is not None
        for line in self.proc.stdout:
            with self._new_line:
                self.lines.append(line.rstrip("\n"))
                self._new_line.notify_all()

    def wait_line(self, prefix: str, timeout: float) -> str | None:
        """The first line starting with ``prefix``, waiting up to ``timeout`` [s]; None if none came."""
        end = time.monotonic() + timeout
        with self._new_line:
            while True:
                found = next((line for line in self.lines if line.startswith(prefix)), None)
                left = end - time.monotonic()
                if found is not None or left <= 0 or (self.proc.poll() is not None and not self._reader.is_alive()):
                    return found
                self._new_line.wait(min(left, 0.2))

    def finish(self, timeout: float) -> int:
        """Wait for the exit code (killing the process group after ``timeout`` [s])."""
        try:
            code = self.proc.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            self.kill()
            raise AssertionError(f"still running {timeout} s later; output:\n{self.output}") from None
        self._reader.join(timeout=5)
        return code

    def kill(self) -> None:
        """Kill the whole process group (idempotent)."""
        if self.proc.poll() is None:
            os.killpg(self.proc.pid, signal.SIGKILL)
            self.proc.wait(timeout=10)

    @property
    def output(self) -> str:
        """Everything printed so far."""
        return "\n".join(self.lines)


def sigcore_run(*args: str, env: dict[str, str] | None = None, sigint: str = "default") -> Proc:
    """``python -m sigcore run ARGS`` (the ROS 2 transport on unless ARGS say otherwise), SIGINT left to it as
    :data:`STARTS` names."""
    return Proc([sys.executable, "-m", "sigcore", "run", *args], env or ros_env(), sigint)


def assert_results(out: str, signal_name: str) -> None:
    """The summary and the referee's score table of the clean-up world are in ``out``, and nothing failed."""
    assert "robots:    1  robot_000" in out and re.search(r"steps: +\d+", out), out
    assert re.search(r"simulated: [\d.]+ s +wall: [\d.]+ s +real-time factor", out), out
    assert f"stopped:  by {signal_name} at t = " in out, out
    assert "referee: {'score': 0, 'result': 'running'" in out, out
    assert re.search(r"^referee \(cleanup rules\): not finished at t = [\d.]+ s, score 0$", out, re.M), out
    assert "Traceback" not in out and "ERROR" not in out, out


# ------------------------------------------------------------------ signals end a run like QUITTING
@needs_ros
def test_sigint_ends_a_ros2_run_with_summary_and_score_table() -> None:
    """SIGINT to `sigcore run` (ROS 2 on by default) prints the summary and the score table, exits 0 (task not
    failed), and the transport stops cleanly: /sigcore/ready goes from true to false."""
    env = ros_env()
    sim = sigcore_run(str(CLEANUP), env=env)
    watch = None
    try:
        assert sim.wait_line("ready: transport 'ros2' is up, running at 1x real time", STARTUP), sim.output
        watch = Proc([sys.executable, str(CLIENTS / "ready_watch.py")], env)
        assert watch.wait_line("ready true", 60.0), watch.output
        sim.proc.send_signal(signal.SIGINT)
        code = sim.finish(30.0)
        assert code == 0, sim.output
        assert_results(sim.output, "SIGINT")
        assert watch.finish(60.0) == 0, watch.output
        assert json.loads(watch.lines[-1]) == {"seen": [True, False]}, watch.output
    finally:
        sim.kill()
        if watch is not None:
            watch.kill()


@needs_ros
@pytest.mark.parametrize(("sig", "sigint"), [(signal.SIGTERM, "default"), (signal.SIGINT, "ignored"),
                                             (signal.SIGINT, "blocked")],
                         ids=["sigterm", "sigint-started-ignored", "sigint-started-blocked"])
def test_signal_ends_a_ros2_run_with_summary_and_score_table(sig: signal.Signals, sigint: str) -> None:
    """SIGTERM to `sigcore run` (ROS 2 on), and SIGINT to one started with SIGINT ignored (a shell's background job)
    or blocked (inherited from a thread that blocked it), print the summary and the score table and exit 0, like
    QUITTING."""
    sim = sigcore_run(str(CLEANUP), sigint=sigint)
    try:
        assert sim.wait_line("ready: transport 'ros2' is up", STARTUP), sim.output
        sim.proc.send_signal(sig)
        assert sim.finish(30.0) == 0, sim.output
        assert_results(sim.output, sig.name)
    finally:
        sim.kill()


@needs_ros
def test_second_signal_while_stopping_aborts() -> None:
    """SIGINT then SIGTERM at once: the second is handled while the run stops and aborts it: exit 130,
    "interrupted", no results."""
    sim = sigcore_run(str(CLEANUP))
    try:
        assert sim.wait_line("ready: transport 'ros2' is up", STARTUP), sim.output
        # both signals pending at once, whatever the scheduler does between two kill() calls: stopped while they
        # are sent, the process receives them together when continued (SIGINT first: they go in number order)
        os.kill(sim.proc.pid, signal.SIGSTOP)
        os.kill(sim.proc.pid, signal.SIGINT)
        os.kill(sim.proc.pid, signal.SIGTERM)
        os.kill(sim.proc.pid, signal.SIGCONT)
        assert sim.finish(30.0) == 130, sim.output
        assert "interrupted (SIGTERM while stopping after SIGINT): no results" in sim.output
        assert "referee (cleanup rules)" not in sim.output
    finally:
        sim.kill()


# ------------------------------------------------------------------ the default transport and pace
def _figures(out: str) -> tuple[float, float]:
    """(wall time [s], real-time factor) from a run's summary."""
    m = re.search(r"wall: ([\d.]+) s +real-time factor: ([\d.]+|inf)", out)
    assert m, out
    return float(m[1]), float(m[2])


@needs_ros
@pytest.mark.parametrize(("flags", "pace"), [((), "at 1x real time"), (("--realtime",), "at 1x real time"),
                                             (("--factor", "4"), "at 4x real time"),
                                             (("--fast",), "as fast as possible")])
def test_ros2_is_the_default_transport_and_paces_at_real_time(flags: tuple[str, ...], pace: str) -> None:
    """Without --transport the ROS 2 transport starts and the pace is real time; --realtime, --factor and --fast
    change it (0.5 simulated seconds; the wall time of a paced run is at least 0.5 / factor s minus 5 %, and
    --fast runs faster than twice real time, about 20x measured on 2 loaded cores)."""
    sim = sigcore_run(str(WORLD), "--steps", "250", "-q", *flags)
    try:
        assert sim.finish(STARTUP) == 0, sim.output
    finally:
        sim.kill()
    assert sim.wait_line(f"ready: transport 'ros2' is up, running {pace};", 0), sim.output
    wall, rtf = _figures(sim.output)
    if pace == "as fast as possible":
        assert rtf > 2.0, sim.output
    else:
        factor = float(pace.split()[1].rstrip("x"))
        assert wall >= 0.95 * 0.5 / factor and rtf <= 1.1 * factor, sim.output


def test_transport_none_is_a_bare_batch_run() -> None:
    """--transport none starts no transport and runs as fast as possible (about 30x measured; asserted > 2x)."""
    sim = sigcore_run(str(WORLD), "--transport", "none", "--steps", "500", "-q")
    try:
        assert sim.finish(STARTUP) == 0, sim.output
    finally:
        sim.kill()
    assert "ready:" not in sim.output and "transport" not in sim.output, sim.output
    assert _figures(sim.output)[1] > 2.0, sim.output


# ------------------------------------------------------------------ world events fired by the simulation itself
class Recorder:
    """A plugin that records the world-level events it receives."""

    def __init__(self) -> None:
        self.calls: list[tuple[str, object]] = []

    @hookimpl
    def sigcore_world_loaded(self, world: World) -> None:
        self.calls.append(("world_loaded", world.name))

    @hookimpl
    def sigcore_simulation_started(self, simulation: Simulation) -> None:
        self.calls.append(("started", simulation.step_count))

    @hookimpl
    def sigcore_simulation_stopped(self, simulation: Simulation) -> None:
        self.calls.append(("stopped", simulation.step_count))


@pytest.fixture
def recorder() -> Iterator[Recorder]:
    """A :class:`Recorder` registered as a plugin beside the installed ones; all are rediscovered afterwards."""
    rec = Recorder()
    plugins.register_plugin(rec, name="lifecycle_recorder")
    yield rec
    plugins.reset_for_tests()


def test_simulation_fires_world_events_without_the_runner(recorder: Recorder, core_world: World) -> None:
    """A library user who only builds and steps a Simulation gets world_loaded, started at the first step, and
    stopped from stop(); stop() is idempotent; a later step starts a new run without calling on_init again."""
    sim = Simulation(core_world, "mujoco")
    assert recorder.calls == [("world_loaded", "coretest")]
    sim.stop()
    assert recorder.calls == [("world_loaded", "coretest")], "stop() before any step fires nothing"
    tracker = trackers.Tracker()
    sim.entities.set_controller("moderator", tracker)
    trackers.CALLS.clear()
    sim.step(3)
    sim.step(2)
    assert recorder.calls[1:] == [("started", 0)]
    sim.stop()
    sim.stop()
    assert recorder.calls[1:] == [("started", 0), ("stopped", 5)]
    sim.step()
    sim.stop()
    assert recorder.calls[1:] == [("started", 0), ("stopped", 5), ("started", 5), ("stopped", 6)]
    assert [c for c in trackers.CALLS if c[1] == "on_init"] == [("moderator", "on_init", 0.0)]


def test_run_starts_and_stops_the_simulation_once_per_run(recorder: Recorder, core_world: World) -> None:
    """run() fires started before its first step and stopped after its last, once each, for every run."""
    sim = Simulation(core_world, "mujoco")
    run(sim, steps=10)
    run(sim, steps=5)
    assert recorder.calls == [("world_loaded", "coretest"), ("started", 0), ("stopped", 10), ("started", 10),
                              ("stopped", 15)]


# ------------------------------------------------------------------ one error root
def _packages() -> list[ModuleType]:
    """The core and every bundled plugin's package (plugins/<dir>/<package>/__init__.py)."""
    names = sorted(p.parent.name for p in ROOT.glob("plugins/*/*/__init__.py") if ".egg-info" not in str(p))
    return [sigcore, *(importlib.import_module(n) for n in names)]


def _exception_classes() -> list[type[BaseException]]:
    found: dict[str, type[BaseException]] = {}
    packages = _packages()
    ours = {p.__name__ for p in packages}
    for package in packages:
        modules = [package]
        for info in pkgutil.walk_packages(package.__path__, f"{package.__name__}."):
            if info.name.rsplit(".", 1)[-1] == "__main__":  # running it would start the command line
                continue
            try:
                modules.append(importlib.import_module(info.name))
            except ModuleNotFoundError as e:  # an optional library this machine lacks (rclpy without ROS 2)
                if (e.name or "sigcore").split(".")[0] in ours:
                    raise
        for module in modules:
            for _, cls in inspect.getmembers(module, inspect.isclass):
                if issubclass(cls, BaseException) and cls.__module__ == module.__name__:
                    found[f"{cls.__module__}.{cls.__qualname__}"] = cls
    return list(found.values())


def test_every_exception_class_derives_from_sigcore_error() -> None:
    """Every exception class defined in sigcore and in the bundled plugins is a SigcoreError (found by walking
    their modules), and the classic ones keep the built-in bases that callers catch."""
    classes = _exception_classes()
    names = {c.__name__ for c in classes}
    assert {"WorldError", "ApiError", "ControllerError", "PluginError", "SimulationError", "FeatureError",
            "BackendError", "UrdfError", "IkError", "BoxGeometryError"} <= names, sorted(names)
    strays = sorted(f"{c.__module__}.{c.__qualname__}" for c in classes if not issubclass(c, SigcoreError))
    assert strays == [], f"not under SigcoreError: {strays}"
    from sigcore.agent.exceptions import ApiError, ControllerError
    from sigcore.errors import BackendError
    from sigcore.world import WorldError

    assert issubclass(ApiError, ValueError) and issubclass(WorldError, ValueError)
    assert issubclass(plugins.PluginError, LookupError) and issubclass(ControllerError, RuntimeError)
    assert issubclass(BackendError, RuntimeError) and sigcore.SigcoreError is SigcoreError
