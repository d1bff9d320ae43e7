"""Processes of the ROS 2 transport tests: a simulation process, client processes, a private ROS domain.

Every process runs in its own session and is killed by process group in ``finally``; each start uses its own
``ROS_DOMAIN_ID`` (``tests/rosdomains.py``: a range per xdist worker) with discovery limited to this machine.
"""

from __future__ import annotations

import contextlib
import json
import os
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path
from typing import TYPE_CHECKING

from rosdomains import next_domain

if TYPE_CHECKING:
    import pytest
    from sigcore_ros2.config import Ros2Config
    from sigcore_ros2.transport import Ros2Transport

    from sigcore.sim import Simulation

HERE = Path(__file__).parent
CLIENTS = HERE / "clients"
WORLD = HERE.parent / "data" / "sim" / "world.xml"
ALL_AGENTS = ("--ros-args", "-p", "sigros_agents:=all")
"""``sigcore run`` arguments giving every agent its sig_ros endpoints (the default, ``auto``, leaves out the objects
without a controller)."""


def _kill(proc: subprocess.Popen[str]) -> None:
    if proc.poll() is None:
        try:
            os.killpg(proc.pid, signal.SIGINT)
            proc.wait(timeout=3)
        except (ProcessLookupError, subprocess.TimeoutExpired):
            pass
    if proc.poll() is None:
        try:
            os.killpg(proc.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
        proc.wait(timeout=5)


@contextlib.contextmanager
def client_process(env: dict[str, str], script: str, *args: str,
                   stdin: bool = False) -> Iterator[subprocess.Popen[str]]:
    """``clients/<script>`` with ``env`` in its own session, stdout and stderr piped (stdin too if asked; see
    :func:`tell_stop`); its process group is killed on leaving the block if it still runs."""
    proc = subprocess.Popen([sys.executable, str(CLIENTS / script), *args], env=env, text=True,
                            stdin=subprocess.PIPE if stdin else None, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, start_new_session=True)
    try:
        yield proc
    finally:
        _kill(proc)


def tell_stop(proc: subprocess.Popen[str]) -> None:
    """Write the line a client that waits on its stdin stops at (nothing if it has ended)."""
    assert proc.stdin is not None
    try:
        proc.stdin.write("stop\n")
        proc.stdin.flush()
    except BrokenPipeError:  # it has ended already
        pass


def last_json(out: str) -> dict:
    """A client's JSON result: the last line it printed."""
    return json.loads(out.strip().splitlines()[-1])


class SimProcess:
    """``python -m sigcore run --transport ros2 WORLD`` in its own session; its log is kept in a file."""

    def __init__(self, env: dict[str, str], world: Path, log: Path, *args: str) -> None:
        self.env, self.log = env, log
        self._log = open(log, "w")  # noqa: SIM115 - closed in stop()
        self.proc = subprocess.Popen([sys.executable, "-m", "sigcore", "run", "--transport", "ros2", "-q",
                                      str(world), *args], env=env, stdout=self._log, stderr=subprocess.STDOUT,
                                     text=True, start_new_session=True)

    def alive(self) -> bool:
        """Whether the simulation process still runs."""
        return self.proc.poll() is None

    def output(self) -> str:
        """Everything the simulation printed and logged so far."""
        self._log.flush()
        return self.log.read_text()

    def stop(self) -> None:
        """Kill the process group."""
        _kill(self.proc)
        self._log.close()

    def client(self, script: str, *args: str, timeout: float = 60.0) -> dict:
        """Run ``clients/<script>`` with this simulation's ROS environment; its JSON result (last line)."""
        proc = subprocess.Popen([sys.executable, str(CLIENTS / script), *args], env=self.env,
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True)
        try:
            out, err = proc.communicate(timeout=timeout)
        except subprocess.TimeoutExpired:
            _kill(proc)
            out, err = proc.communicate()
            raise AssertionError(f"client {script} timed out after {timeout} s; stderr:\n{err[-3000:]}") from None
        finally:
            _kill(proc)
        lines = [line for line in out.splitlines() if line.startswith("{")]
        assert proc.returncode == 0 and lines, \
            f"client {script} failed ({proc.returncode}):\n{out[-2000:]}\n{err[-3000:]}"
        return json.loads(lines[-1])


def ros_env() -> dict[str, str]:
    """The environment of a test's processes: a private domain, discovery on this machine only."""
    env = dict(os.environ)
    env["ROS_DOMAIN_ID"] = str(next_domain())
    env["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
    env["PYTHONUNBUFFERED"] = "1"
    # a client that dies of a signal says where: once, in CI, ready.py died of SIGSEGV (-11) before printing anything
    # (inside rclpy's or Fast DDS's native code; 90 starts against a running simulator here did not reproduce it)
    env["PYTHONFAULTHANDLER"] = "1"
    env.pop("ROS_STATIC_PEERS", None)
    return env


def start_sim(tmp: Path, world: Path = WORLD, *args: str) -> SimProcess:
    """Start a simulation and wait (bounded) for it to announce readiness."""
    sim = SimProcess(ros_env(), world, tmp / "sim.log", *args)
    try:
        ready = sim.client("ready.py", timeout=90)
        assert ready["ready"], sim.output()
    except BaseException:
        sim.stop()
        raise
    return sim


def client_against(tmp: Path, world: Path, script: str, *args: str, sim_args: tuple[str, ...] = (),
                   timeout: float = 180.0) -> Iterator[dict]:
    """Start a simulation of ``world`` (``sim_args`` on its command line), run the client ``script`` against it,
    yield what the client emitted (the simulation still running), and stop the simulation at the end."""
    sim = start_sim(tmp, world, *sim_args)
    try:
        result = sim.client(script, *args, timeout=timeout)
        assert sim.alive(), sim.output()
        yield result
    finally:
        sim.stop()


def wait_until(predicate: object, timeout: float = 10.0) -> bool:
    """Poll ``predicate()`` every 50 ms up to ``timeout`` [s]."""
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if predicate():  # type: ignore[operator]
            return True
        time.sleep(0.05)
    return False


def start_in_process(monkeypatch: pytest.MonkeyPatch, world: Path, config: Ros2Config | None = None,
                     ) -> tuple[Simulation, Ros2Transport, dict[str, str]]:
    """A paused simulation of ``world`` (MuJoCo) with the ROS 2 transport started in this process (with
    ``config``; default: the world's settings), in the test's own ROS domain (``monkeypatch`` sets it here):
    ``(sim, transport, environment for client processes)``; the caller stops the transport."""
    from sigcore_ros2.transport import Ros2Transport

    from sigcore.sim import Simulation
    from sigcore.world import parse_world

    env = ros_env()
    for key in ("ROS_DOMAIN_ID", "ROS_AUTOMATIC_DISCOVERY_RANGE"):
        monkeypatch.setenv(key, env[key])
    sim = Simulation(parse_world(world), "mujoco")
    sim.control.pause()
    transport = Ros2Transport(config)
    transport.start(sim)
    return sim, transport, env
