"""Every exit code of ``sigcore run`` in the table of README.md and docs/reliability.md, each produced by a real run
of the real command in a subprocess (``--transport none``: no ROS 2 needed): 0, 1, 2, 3 and 130."""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

from sigcore import plugins

ROOT = Path(__file__).parent.parent
CLEANUP = ROOT / "worlds" / "cleanup.xml"
SIGCORE = [sys.executable, "-m", "sigcore"]

PLAIN = """<world name="plain" timestep="0.002">
  <object name="box" shape="box" size="0.1 0.1 0.1" pose="0 0 0.05"/>
  {agent}
</world>
"""

HANGING = '''
import sys
import time

from sigcore.agent import Controller


class Hangs(Controller):
    """Says so on stdout, then stays in on_action for a minute (a controller stuck in user code)."""

    def on_action(self, ctx):
        print("on_action: hanging", flush=True)
        time.sleep(60)
        return 1.0
'''

FAULTY_TRANSPORT = '''
import sigcore
from sigcore.transport import Transport


class Faulty(Transport):
    """A transport (not user code) whose step observer has a bug at step 100."""

    name = "faulty"

    def start(self, sim):
        def observer(s):
            if s.step_count == 100:
                raise RuntimeError("transport bug")
        sim.events.subscribe("step", observer)

    def stop(self):
        pass

    def service(self, timeout):
        pass


@sigcore.hookimpl
def sigcore_register_transports(register):
    register(Faulty)
'''


def sigcore(*args: str, cwd: Path = ROOT, env: dict[str, str] | None = None,
            timeout: float = 300) -> subprocess.CompletedProcess[str]:
    """The real ``sigcore`` command."""
    return subprocess.run([*SIGCORE, *args], capture_output=True, text=True, cwd=cwd, timeout=timeout,
                          env=env or os.environ.copy())


def cleanup_with(tmp_path: Path, **referee: str) -> Path:
    """worlds/cleanup.xml with the referee's attributes changed (written beside its models by absolute paths)."""
    text = CLEANUP.read_text()
    for key, value in referee.items():
        text, n = re.subn(rf'({key}=")[^"]*(")', rf"\g<1>{value}\g<2>", text, count=1)
        assert n == 1, key
    text = text.replace('urdf="models/', f'urdf="{CLEANUP.parent}/models/')
    path = tmp_path / "cleanup.xml"
    path.write_text(text)
    return path


def plain(tmp_path: Path, agent: str = "") -> Path:
    """A world without a task (no feature gives a verdict)."""
    path = tmp_path / "plain.xml"
    path.write_text(PLAIN.format(agent=agent))
    return path


# ------------------------------------------------------------------ 0
@pytest.mark.slow
def test_exit_0_when_the_world_has_no_task(tmp_path: Path) -> None:
    """A run of a world with no feature that gives a verdict exits 0."""
    r = sigcore("run", str(plain(tmp_path)), "--transport", "none", "--steps", "100", "-q")
    assert r.returncode == 0, r.stdout + r.stderr
    assert "steps:    100" in r.stdout


@pytest.mark.slow
def test_exit_0_when_the_task_succeeded() -> None:
    """The clean-up task solved by the scripted controller: the referee says succeeded, the run exits 0."""
    r = sigcore("run", str(CLEANUP), "--transport", "none", "--controller", "robot_000=cleanup.robot",
                "--duration", "300", "-q")
    assert r.returncode == 0, r.stdout[-3000:] + r.stderr[-3000:]
    assert "referee (cleanup rules): succeeded at t = " in r.stdout


@pytest.mark.slow
def test_exit_0_when_the_run_ends_before_the_task_does() -> None:
    """--duration shorter than the task: the referee says "not finished" (no verdict), the run exits 0."""
    r = sigcore("run", str(CLEANUP), "--transport", "none", "--duration", "1", "-q")
    assert r.returncode == 0, r.stdout + r.stderr
    assert "referee (cleanup rules): not finished at t = 1.00 s, score 0" in r.stdout


@pytest.mark.slow
def test_exit_0_after_one_sigint_when_the_task_has_not_ended(tmp_path: Path) -> None:
    """One SIGINT ends a running batch run like a stop request: results printed, exit by the verdict (none: 0)."""
    proc = subprocess.Popen([*SIGCORE, "run", str(plain(tmp_path)), "--transport", "none", "--duration", "100000"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=ROOT,
                            start_new_session=True)
    try:
        assert proc.stderr is not None
        for line in proc.stderr:  # progress lines come every 2 s of wall time once stepping
            if line.strip().startswith("t = "):
                break
        proc.send_signal(signal.SIGINT)
        out, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
    assert proc.returncode == 0, out + err
    assert "stopped:  by SIGINT at t = " in out


# ------------------------------------------------------------------ 1
@pytest.mark.slow
def test_exit_1_when_the_referee_time_limit_comes_first(tmp_path: Path) -> None:
    """The referee's time limit (1 s) reached with nothing done: result time_limit, the run exits 1."""
    world = cleanup_with(tmp_path, time_limit="1")
    r = sigcore("run", str(world), "--transport", "none", "--duration", "5", "-q")
    assert r.returncode == 1, r.stdout + r.stderr
    assert "referee (cleanup rules): time_limit at t = 1.00 s" in r.stdout
    assert "steps:    500" in r.stdout  # stop_on_finish: the run ended with the task, not at 5 s


@pytest.mark.slow
def test_exit_1_when_the_time_limit_equals_the_duration(tmp_path: Path) -> None:
    """--duration equal to the referee's time limit gives the verdict (time_limit, exit 1), not "not finished"."""
    world = cleanup_with(tmp_path, time_limit="2")
    r = sigcore("run", str(world), "--transport", "none", "--duration", "2", "-q")
    assert r.returncode == 1, r.stdout + r.stderr
    assert "referee (cleanup rules): time_limit at t = 2.00 s" in r.stdout


# ------------------------------------------------------------------ 2
@pytest.mark.slow
@pytest.mark.parametrize(("args", "says"), [
    (["run", "WORLD", "--transport", "none", "--backend", "nosuch"], "nosuch"),
    (["run", "WORLD", "--transport", "none", "--duration", "-1"], "--duration"),
    (["run", "WORLD", "--transport", "nosuch", "--steps", "1"], "nosuch"),
    (["run", "BROKEN", "--transport", "none", "--steps", "1"], "broken.xml:2:"),
    (["run", "WORLD", "--transport", "none", "--controller", "box=no.such:Module", "--steps", "1"], "no.such"),
])
def test_exit_2_when_the_world_or_an_option_is_invalid(tmp_path: Path, args: list[str], says: str) -> None:
    """An invalid world, option, transport, backend or controller: exit 2, the message names it, nothing ran."""
    broken = tmp_path / "broken.xml"
    broken.write_text('<world name="b" timestep="0.002">\n  <object name="x" shape="cube" size="1"/>\n</world>\n')
    args = [str(plain(tmp_path)) if a == "WORLD" else str(broken) if a == "BROKEN" else a for a in args]
    r = sigcore(*args)
    assert r.returncode == 2, r.stdout + r.stderr
    assert says in r.stderr and "Traceback" not in r.stderr, r.stderr
    assert "steps:" not in r.stdout


def install_faulty_transport(tmp_path: Path) -> Path:
    """Install the faulty transport plugin as a distribution (a ``*.dist-info`` with an entry point) in a folder."""
    site = tmp_path / "site"
    site.mkdir()
    (site / "sigcore_exit_faulty.py").write_text(textwrap.dedent(FAULTY_TRANSPORT))
    info = site / "sigcore_exit_faulty-0.1.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: sigcore-exit-faulty\nVersion: 0.1\n")
    (info / "entry_points.txt").write_text(f"[{plugins.GROUP}]\nfaulty = sigcore_exit_faulty\n")
    return site


# ------------------------------------------------------------------ 3
@pytest.mark.slow
def test_exit_3_when_the_run_stops_on_an_error_outside_user_code(tmp_path: Path) -> None:
    """A bug in an installed transport plugin while stepping: the report is printed, the error named, exit 3."""
    site = install_faulty_transport(tmp_path)
    r = sigcore("run", str(plain(tmp_path)), "--transport", "faulty", "--fast", "--steps", "300", "-q",
                env={**os.environ, "PYTHONPATH": str(site)})
    assert r.returncode == 3, r.stdout + r.stderr
    assert "steps:    100" in r.stdout
    assert "stopped:  by an error at t = 0.200 s (not in user code: see the log): RuntimeError: transport bug" \
        in r.stdout


# ------------------------------------------------------------------ 130
def test_exit_130_on_a_second_sigint(tmp_path: Path) -> None:
    """A controller hangs in on_action: the first SIGINT asks the run to stop (it cannot, the callback has not
    returned), the second aborts it: exit 130, "interrupted", no results."""
    site = tmp_path / "site"
    site.mkdir()
    (site / "exit_hangs.py").write_text(HANGING)
    world = plain(tmp_path, '<agent name="moderator" controller="exit_hangs:Hangs"/>')
    proc = subprocess.Popen([*SIGCORE, "run", str(world), "--transport", "none", "--duration", "10", "-q"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=ROOT,
                            env={**os.environ, "PYTHONPATH": str(site)}, start_new_session=True)
    try:
        assert proc.stdout is not None
        for line in proc.stdout:
            if line.startswith("on_action: hanging"):
                break
        proc.send_signal(signal.SIGINT)
        time.sleep(0.5)  # the callback sleeps 60 s: both signals land in it, whatever the load
        proc.send_signal(signal.SIGINT)
        out, err = proc.communicate(timeout=30)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
    assert proc.returncode == 130, out + err
    assert "interrupted (SIGINT while stopping after SIGINT): no results" in err
    assert "steps:" not in out


def exit_table(path: Path) -> str:
    """The exit-code table of ``path`` (from its header row to the first line that is not a row)."""
    lines = path.read_text().splitlines()
    start = lines.index("| code | `sigcore run` ended because |")
    end = next(i for i in range(start, len(lines)) if not lines[i].startswith("|"))
    return "\n".join(lines[start:end])


def test_the_readme_and_the_reliability_page_have_the_same_table_of_the_codes_tested_here() -> None:
    """README.md and docs/reliability.md show one table, and it lists exactly the codes this file tests."""
    table = exit_table(ROOT / "README.md")
    assert table == exit_table(ROOT / "docs" / "reliability.md")
    codes = {int(row.split("|")[1]) for row in table.splitlines()[2:]}
    tested = {int(m) for m in re.findall(r"^def test_exit_(\d+)_", Path(__file__).read_text(), re.M)}
    assert codes == tested == {0, 1, 2, 3, 130}
