"""One episode of an evaluation: the world drawn with the episode's seed, the simulator and the user's solution as
process groups of their own in a ROS 2 domain of their own, their ends classified, their results and logs kept.

:func:`run_episode` takes plain values and imports nothing of the simulator, so a Ray worker runs it as it is. It
never raises for what an episode does: a crash, a hang or a simulator error is its row's ``status``.
"""

from __future__ import annotations

import json
import os
import signal
import socket
import subprocess
import sys
import threading
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path

from .domains import DOMAINS, DomainLease

STATUSES = ("done", "timeout", "not_started", "solution_crashed", "simulator_error")
"""How an episode ended: ``done`` (the simulator ended by itself: the task's end, its duration), ``timeout`` (the
wall-time limit; both were stopped), ``not_started`` (the wall-time limit came while the simulation was still at
t = 0, not one step taken: with ``--wait-for``, the solution never had the awaited topics' peers), ``solution_crashed``
(the solution exited non-zero while the simulator ran or waited; the simulator was stopped), ``simulator_error`` (the
simulator failed or left no results)."""

INTERRUPTED = "interrupted"
"""The status of an episode the evaluation stopped (Ctrl-C): not recorded, run again by ``--resume``."""

SIM_STOP = signal.SIGTERM
"""The signal that stops a simulator: during its run ``sigcore run`` takes it as SIGINT (it stops and writes its
results); while Python is still starting (importing), its default action ends the process without the traceback a
SIGINT (``KeyboardInterrupt``) would print there."""

SOLUTION_STOP = signal.SIGINT
"""The signal that stops a solution (as Ctrl-C would: ``ros2 launch`` and rclpy nodes end cleanly on it)."""

STOP_GRACE = 10.0
"""Wall time a stopped process group has to end after its stop signal before it is killed [s]."""

POLL = 0.1
"""How often the processes are looked at [s]."""


@dataclass(frozen=True)
class EpisodeSpec:
    """What an episode runs (plain values: it travels to a Ray worker as it is).

    Attributes:
        index: The episode's number, from 0.
        seed: The seed its world is drawn with (``sigcore run --seed``).
        world: The world file (absolute).
        out: The evaluation's folder; the episode keeps its files in ``episodes/NNNN`` there.
        solution: The shell command of the solution (run with ``/bin/sh -c`` in ``cwd``), or None for
            ``controllers`` alone (no ROS 2).
        controllers: ``AGENT=CONTROLLER`` for ``sigcore run --controller`` (in-process, without ROS 2).
        backend: The physics backend.
        timeout: Wall-time limit of the episode [s].
        pace: ``sigcore run`` options that pace the simulation (e.g. ``["--factor", "2.5"]``, ``["--fast"]``).
        wait_for: Topics the simulator waits for before it plays (``--wait-for``).
        cwd: The solution's working folder.
        python: The Python that runs ``sigcore`` (the driver's; on Ray, the worker's when None).
        duration: The simulator's ``--duration``: at most this much simulated time [s] (the task's end, e.g. the
            referee's time limit, usually comes first).
        domains: The ``ROS_DOMAIN_ID`` range the episode takes its domain from, ``(LOW, HIGH)``, both included.
    """

    index: int
    seed: int
    world: str
    out: str
    solution: str | None = None
    controllers: tuple[str, ...] = ()
    backend: str = "mujoco"
    timeout: float = 600.0
    pace: tuple[str, ...] = ()
    wait_for: tuple[str, ...] = ()
    cwd: str | None = None
    python: str | None = None
    duration: float = 3600.0
    domains: tuple[int, int] = (DOMAINS.start, DOMAINS.stop - 1)

    @property
    def folder(self) -> Path:
        """Where the episode's logs and results go."""
        return Path(self.out) / "episodes" / f"{self.index:04d}"


@dataclass
class EpisodeRow:
    """What an episode did: one row of ``episodes.csv``.

    Attributes:
        episode: Its number.
        seed: Its world's seed.
        status: One of :data:`STATUSES`.
        success: Whether the world's task succeeded (the simulator's verdict; False unless ``done``).
        result: The referee's result (``succeeded``, ``failed``, ``time_limit``, ``running``), or empty.
        score: The referee's score, or None without one.
        events: The referee's events by kind, e.g. ``grasp:3 correct_box:3 end:1``.
        sim_time: Simulated time of the run [s], or None without results.
        wall_time: Wall time of the episode, from the simulator's start to both processes' end [s].
        sim_exit: The simulator's exit code (None if it was killed).
        solution_exit: The solution's exit code (None without one, or if it was killed).
        domain: Its ROS_DOMAIN_ID.
        host: The machine it ran on.
        reason: Why it was not ``done``, in words (empty when done).
        folder: Its logs (``sim.log``, ``solution.log``) and results (``result.json``).
    """

    episode: int
    seed: int
    status: str
    success: bool
    result: str = ""
    score: float | None = None
    events: str = ""
    sim_time: float | None = None
    wall_time: float = 0.0
    sim_exit: int | None = None
    solution_exit: int | None = None
    domain: int | None = None
    host: str = field(default_factory=socket.gethostname)
    reason: str = ""
    folder: str = ""

    def as_dict(self) -> dict[str, object]:
        """The row's values by column name."""
        return asdict(self)


def run_episode(spec: EpisodeSpec, stop: threading.Event | None = None) -> EpisodeRow:
    """Run ``spec`` to its end and classify it (never raises for what the episode does; an exception from outside,
    such as KeyboardInterrupt, still ends both process groups before it goes on).

    Args:
        spec: The episode.
        stop: Set by the evaluation to stop the episode now: both processes are ended and the row's status is
            :data:`INTERRUPTED`.
    """
    folder = spec.folder
    folder.mkdir(parents=True, exist_ok=True)
    results = folder / "result.json"
    results.unlink(missing_ok=True)
    with DomainLease(range(spec.domains[0], spec.domains[1] + 1)) as domain:
        env = {**os.environ, "ROS_DOMAIN_ID": str(domain), "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST",
               "PYTHONUNBUFFERED": "1", "SIGCORE_EPISODE": str(spec.index), "SIGCORE_SEED": str(spec.seed)}
        t0 = time.monotonic()
        sim = solution = None
        status, reason = INTERRUPTED, "the evaluation was interrupted"
        try:
            sim = _start(_sim_command(spec, results), env, folder / "sim.log", None)
            if spec.solution is not None:
                solution = _start(["/bin/sh", "-c", spec.solution], env, folder / "solution.log", spec.cwd)
            status, reason = _watch(sim, solution, spec.timeout, t0, stop)
        finally:
            if solution is not None:
                _stop(solution, SOLUTION_STOP)
            if sim is not None and sim.poll() is None:
                stopped = time.monotonic() - t0
                _stop(sim, SIM_STOP)
                _note_stop(folder / "sim.log", sim, stopped, reason)
            elif sim is not None:
                _stop(sim, SIM_STOP)  # what is left of its group
        wall = time.monotonic() - t0
    assert sim is not None
    row = EpisodeRow(spec.index, spec.seed, status, False, wall_time=round(wall, 3), sim_exit=_code(sim),
                     solution_exit=_code(solution) if solution is not None else None, domain=domain, reason=reason,
                     folder=str(folder))
    _read_results(row, results, spec)
    return row


def _sim_command(spec: EpisodeSpec, results: Path) -> list[str]:
    command = [spec.python or sys.executable, "-m", "sigcore", "run", spec.world, "--seed", str(spec.seed),
               "--backend", spec.backend, "--results", str(results), "--quiet", "--duration", f"{spec.duration:g}",
               *spec.pace]
    if spec.solution is None:
        command += ["--transport", "none"]
    else:
        command += ["--transport", "ros2"]
        for topic in spec.wait_for:
            command += ["--wait-for", topic]
    for controller in spec.controllers:
        command += ["--controller", controller]
    return command


def _start(command: list[str], env: dict[str, str], log: Path, cwd: str | None) -> subprocess.Popen[bytes]:
    with open(log, "wb") as out:
        return subprocess.Popen(command, env=env, cwd=cwd, stdin=subprocess.DEVNULL, stdout=out,
                                stderr=subprocess.STDOUT, start_new_session=True)


def _watch(sim: subprocess.Popen[bytes], solution: subprocess.Popen[bytes] | None, timeout: float,
           t0: float, stop: threading.Event | None) -> tuple[str, str]:
    """Wait for the simulator's end, the solution's crash, the timeout or ``stop``; how the episode ended."""
    while True:
        if stop is not None and stop.is_set():
            return INTERRUPTED, "the evaluation was interrupted"
        if sim.poll() is not None:
            return "done", ""
        if solution is not None and solution.poll() not in (None, 0):
            return "solution_crashed", f"the solution exited {solution.returncode}"
        if time.monotonic() - t0 > timeout:
            return "timeout", f"not ended within {timeout:g} s of wall time"
        time.sleep(POLL)


def _stop(proc: subprocess.Popen[bytes], sig: signal.Signals) -> None:
    """End ``proc``'s whole process group: ``sig`` (the simulator writes its results), then SIGKILL for what is left
    after :data:`STOP_GRACE` s."""
    try:
        if proc.poll() is None:
            os.killpg(proc.pid, sig)
            try:
                proc.wait(timeout=STOP_GRACE)
            except subprocess.TimeoutExpired:
                pass
        os.killpg(proc.pid, signal.SIGKILL)  # what is left of the group (a solution's children)
    except ProcessLookupError:
        pass
    proc.wait()


def _note_stop(log: Path, sim: subprocess.Popen[bytes], at: float, why: str) -> None:
    """One line at the end of ``sim.log`` on why and how the evaluation stopped the simulator."""
    code = sim.returncode
    how = ("it was still starting (no results)" if code == -SIM_STOP else
           f"it was killed (SIGKILL), still running {STOP_GRACE:g} s later" if code == -signal.SIGKILL else
           f"it ended its run and exited {code}")
    try:
        with open(log, "a") as f:
            f.write(f"sigcore eval: stopped the simulator ({SIM_STOP.name}) {at:.1f} s into the episode: {why}; "
                    f"{how}\n")
    except OSError:
        pass


def _code(proc: subprocess.Popen[bytes]) -> int | None:
    """The exit code; None when a signal ended the process."""
    code = proc.returncode
    return code if code is not None and code >= 0 else None


def _read_results(row: EpisodeRow, path: Path, spec: EpisodeSpec) -> None:
    """Fill ``row`` from the simulator's ``--results`` file; a missing or unreadable one is a simulator error; a
    timed-out episode whose simulation took no step is ``not_started``."""
    try:
        data = json.loads(path.read_text())
    except (OSError, ValueError) as e:
        if row.status == "solution_crashed":
            row.reason += " while the simulator was starting (no results)"
        elif row.status == "timeout":
            row.reason += "; the simulator left no results (see sim.log)"
        if row.status == "done":
            row.status, row.reason = "simulator_error", (f"no results ({e.__class__.__name__}); exit code "
                                                          f"{row.sim_exit}; see sim.log")
        return
    row.sim_time = data.get("sim_time_run")
    if data.get("steps") == 0:
        if row.status == "timeout":
            row.status = "not_started"
            row.reason = (f"the simulation was still at t = 0 after --timeout {spec.timeout:g} s: " + (
                f"it waited for --wait-for {' '.join(spec.wait_for)}, whose peers the solution never had (sim.log "
                "names the ones missing)" if spec.wait_for else "paused, and nothing played or stepped it"))
        elif row.status == "solution_crashed":
            row.reason += " before the simulation left t = 0"
    elif row.status == "solution_crashed":
        row.reason += f" while the simulation ran (at t = {data.get('sim_time', 0):.2f} s)"
    if row.status == "done" and data.get("exit_code") == 3:
        row.status, row.reason = "simulator_error", str(data.get("error"))
    elif row.status == "done" and row.sim_exit not in (0, 1):
        row.status, row.reason = "simulator_error", f"the simulator exited {row.sim_exit}; see sim.log"
    for values in (data.get("features") or {}).values():
        if isinstance(values, dict) and "score" in values:
            score = values.get("score")
            row.score = float(score) if isinstance(score, int | float) else None
            row.result = str(values.get("result", ""))
            kinds: dict[str, int] = {}
            for event in values.get("events", []):
                kinds[event["kind"]] = kinds.get(event["kind"], 0) + 1
            row.events = " ".join(f"{k}:{n}" for k, n in kinds.items())
            break
    row.success = row.status == "done" and data.get("outcome") is True
