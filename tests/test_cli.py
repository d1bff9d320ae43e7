"""The command line: run, check, api, plugins, interfaces; errors as path: message with exit code 2."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

from sigcore.api.docs import api_markdown
from sigcore.api.interfaces import interface_files

ROOT = Path(__file__).parent.parent
WORLD = ROOT / "tests" / "data" / "sim" / "world.xml"


def sigcore(*args: str, cwd: Path = ROOT) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "sigcore", *args], capture_output=True, text=True, cwd=cwd,
                          timeout=120)


def test_run_prints_what_ran() -> None:
    """`sigcore run --steps` prints agents, steps, simulated time, wall time and real-time factor."""
    r = sigcore("run", str(WORLD), "--steps", "250", "--quiet")
    assert r.returncode == 0, r.stderr
    assert "robots:" in r.stdout and "bot" in r.stdout and "moderator" in r.stdout
    assert "steps:    250" in r.stdout
    assert "simulated: 0.500 s" in r.stdout and "real-time factor" in r.stdout


def test_check_reports_located_errors_with_exit_2(tmp_path: Path) -> None:
    """`sigcore check` prints each problem as file:line:column: message, exit code 2, no traceback."""
    bad = tmp_path / "bad.xml"
    bad.write_text('<world>\n  <object name="a" shape="cube" size="1"/>\n  <robot name="r"/>\n</world>\n')
    r = sigcore("check", str(bad))
    assert r.returncode == 2
    lines = r.stderr.strip().splitlines()
    assert lines[0].startswith(f"{bad}:2:") and "box" in lines[0] and "sphere" in lines[0]
    assert any(line.startswith(f"{bad}:3:") and "'urdf'" in line for line in lines)
    assert "Traceback" not in r.stderr


def test_check_ok() -> None:
    """`sigcore check` of a valid world says ok and exits 0."""
    r = sigcore("check", str(WORLD))
    assert r.returncode == 0 and "ok (7 agents" in r.stdout


def test_unknown_backend_lists_valid_ones() -> None:
    """An unknown --backend is refused with the installed ones listed."""
    r = sigcore("run", str(WORLD), "--backend", "bulet", "--steps", "1")
    assert r.returncode == 2 and "mujoco" in r.stderr and "bulet" in r.stderr


def test_missing_world_file() -> None:
    """A missing world file is a usage error, not a traceback."""
    r = sigcore("check", "nosuch.xml")
    assert r.returncode == 2 and "Traceback" not in r.stderr


def test_paused_without_transport_is_refused() -> None:
    """--paused without a transport would never resume: refused with a hint."""
    r = sigcore("run", str(WORLD), "--paused")
    assert r.returncode == 2 and "--transport" in r.stderr


def test_api_lists_every_agent() -> None:
    """`sigcore api WORLD` lists each agent with its endpoint count and the total."""
    r = sigcore("api", str(WORLD))
    assert r.returncode == 0
    assert "bot (robot): 49 endpoints" in r.stdout and "7 agents, 306 endpoints" in r.stdout


def test_plugins_lists_mujoco() -> None:
    """`sigcore plugins` shows the MuJoCo backend with its distribution and version."""
    r = sigcore("plugins")
    assert r.returncode == 0 and "sigcore-backend-mujoco" in r.stdout and "0.1.0" in r.stdout


def test_api_doc_is_current() -> None:
    """docs/api.md is what `sigcore api --markdown` generates from the table."""
    assert (ROOT / "docs" / "api.md").read_text().strip() == api_markdown().strip()


def test_interface_files_are_current() -> None:
    """interfaces/sigcore_msgs holds exactly the files generated from the API table."""
    pkg = ROOT / "interfaces" / "sigcore_msgs"
    for rel, text in interface_files().items():
        assert (pkg / rel).read_text() == text, f"{rel} is stale: run sigcore interfaces"


def test_controller_option_attaches_and_validates() -> None:
    """--controller AGENT=NAME attaches a controller; a bad form or an unknown agent is refused with exit 2."""
    r = subprocess.run([sys.executable, "-m", "sigcore", "run", str(WORLD), "--steps", "50", "--quiet",
                        "--controller", "moderator=trackers:Raising"], capture_output=True, text=True, cwd=ROOT,
                       timeout=120, env={**os.environ, "PYTHONPATH": str(ROOT / "tests")})
    assert r.returncode == 0, r.stderr
    assert "controller of 'moderator' disabled (on_action" in r.stdout and "boom" in r.stdout
    r = sigcore("run", str(WORLD), "--steps", "5", "--controller", "moderator")
    assert r.returncode == 2 and "AGENT=CONTROLLER" in r.stderr
    r = sigcore("run", str(WORLD), "--steps", "5", "--controller", "nobody=cleanup.robot")
    assert r.returncode == 2 and "no agent 'nobody'" in r.stderr
    r = sigcore("run", str(WORLD), "--steps", "5", "--controller", "moderator=no.such:Thing")
    assert r.returncode == 2 and ":" in r.stderr.splitlines()[0] and "cannot import module 'no.such'" in r.stderr
