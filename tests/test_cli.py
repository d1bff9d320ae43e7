"""The command line: run, check, api, plugins, interfaces; errors as path: message with exit code 2."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from sigcore.api.docs import api_markdown
from sigcore.api.interfaces import interface_files

ROOT = Path(__file__).parent.parent
WORLD = ROOT / "tests" / "data" / "sim" / "world.xml"


def sigcore(*args: str, cwd: Path = ROOT) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "sigcore", *args], capture_output=True, text=True, cwd=cwd,
                          timeout=120)


@pytest.mark.slow
def test_run_prints_what_ran() -> None:
    """`sigcore run --steps` prints agents, steps, simulated time, wall time and real-time factor."""
    r = sigcore("run", str(WORLD), "--transport", "none", "--steps", "250", "--quiet")
    assert r.returncode == 0, r.stderr
    assert "robots:" in r.stdout and "bot" in r.stdout and "moderator" in r.stdout
    assert "steps:    250" in r.stdout
    assert "simulated: 0.500 s" in r.stdout and "real-time factor" in r.stdout


@pytest.mark.slow
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


@pytest.mark.slow
def test_check_ok() -> None:
    """`sigcore check` of a valid world says ok and exits 0."""
    r = sigcore("check", str(WORLD))
    assert r.returncode == 0 and "ok (7 agents" in r.stdout


@pytest.mark.slow
def test_unknown_backend_lists_valid_ones() -> None:
    """An unknown --backend is refused with the installed ones listed."""
    r = sigcore("run", str(WORLD), "--transport", "none", "--backend", "bulet", "--steps", "1")
    assert r.returncode == 2 and "mujoco" in r.stderr and "bulet" in r.stderr


@pytest.mark.slow
def test_missing_world_file() -> None:
    """A missing world file is a usage error, not a traceback."""
    r = sigcore("check", "nosuch.xml")
    assert r.returncode == 2 and "Traceback" not in r.stderr


@pytest.mark.slow
def test_paused_without_transport_is_refused() -> None:
    """--paused without a transport would never resume: refused with a hint."""
    r = sigcore("run", str(WORLD), "--paused", "--transport", "none")
    assert r.returncode == 2 and "--paused needs a transport" in r.stderr and "--transport none" in r.stderr


@pytest.mark.slow
def test_api_lists_every_agent() -> None:
    """`sigcore api WORLD` lists each agent with its endpoint count (a plain object none over ROS 2: the shared
    /sigcore/sigros/<function> endpoints serve it), the other endpoints and the total."""
    r = sigcore("api", str(WORLD))
    assert r.returncode == 0
    assert "bot (robot): 53 endpoints" in r.stdout and "cube (object): 0 endpoints" in r.stdout
    assert "7 agents, 142 agent endpoints, 73 others, 215 in all" in r.stdout
    assert "/sigcore/sigros/get_obj_position" in r.stdout
    assert "/tf_static" in r.stdout and "/bot/cmd_vel" in r.stdout and "/man/cmd_vel" in r.stdout


@pytest.mark.slow
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


@pytest.mark.slow
def test_controller_option_attaches_and_validates() -> None:
    """--controller AGENT=NAME attaches a controller; a bad form or an unknown agent is refused with exit 2."""
    r = subprocess.run([sys.executable, "-m", "sigcore", "run", str(WORLD), "--transport", "none", "--steps", "50",
                        "--quiet", "--controller", "moderator=trackers:Raising"], capture_output=True, text=True,
                       cwd=ROOT, timeout=120, env={**os.environ, "PYTHONPATH": str(ROOT / "tests")})
    assert r.returncode == 0, r.stderr
    assert "controller of 'moderator' disabled (on_action" in r.stdout and "boom" in r.stdout
    r = sigcore("run", str(WORLD), "--transport", "none", "--steps", "5", "--controller", "moderator")
    assert r.returncode == 2 and "AGENT=CONTROLLER" in r.stderr
    r = sigcore("run", str(WORLD), "--transport", "none", "--steps", "5", "--controller", "nobody=cleanup.robot")
    assert r.returncode == 2 and "no agent 'nobody'" in r.stderr
    r = sigcore("run", str(WORLD), "--transport", "none", "--steps", "5", "--controller",
                "moderator=no.such:Thing")
    assert r.returncode == 2 and ":" in r.stderr.splitlines()[0] and "cannot import module 'no.such'" in r.stderr


@pytest.mark.slow
def test_pace_options_exclude_each_other() -> None:
    """Two of --fast, --realtime and --factor are refused with exit 2, naming both and the three choices."""
    for flags in (["--fast", "--factor", "2"], ["--realtime", "--factor", "2"], ["--fast", "--realtime"]):
        r = sigcore("run", str(WORLD), "--transport", "none", "--steps", "5", *flags)
        given = [f for f in flags if f.startswith("--")]
        assert r.returncode == 2 and f"{given[0]} and {given[1]} exclude each other" in r.stderr, r.stderr
        assert "--fast (as fast as possible)" in r.stderr and "--factor F" in r.stderr


@pytest.mark.slow
def test_unknown_transport_lists_valid_ones() -> None:
    """An unknown --transport is refused with exit 2, the registered ones listed and 'none' offered."""
    r = sigcore("run", str(WORLD), "--transport", "ros3", "--steps", "5")
    assert r.returncode == 2 and "'ros3' is not registered" in r.stderr and "ros2" in r.stderr
    assert "'none'" in r.stderr


def without_rclpy(tmp_path: Path) -> dict[str, str]:
    """The environment of a machine without ROS 2: a package ``rclpy`` first on the path that fails to import."""
    (tmp_path / "rclpy").mkdir()
    (tmp_path / "rclpy" / "__init__.py").write_text('raise ImportError("no ROS 2 on this machine")\n')
    return {**os.environ, "PYTHONPATH": str(tmp_path)}


@pytest.mark.slow
def test_without_rclpy_the_default_run_is_bare_and_says_so(tmp_path: Path) -> None:
    """Where rclpy cannot be imported, `sigcore run` says so in one line and runs without a transport, as fast as
    possible; an explicit --transport ros2 or --paused is refused with the reason."""
    env = without_rclpy(tmp_path)
    r = subprocess.run([sys.executable, "-m", "sigcore", "run", str(WORLD), "--steps", "50", "-q"],
                       capture_output=True, text=True, cwd=ROOT, timeout=120, env=env)
    assert r.returncode == 0, r.stderr
    lines = [line for line in r.stderr.splitlines() if "transport" in line]
    assert len(lines) == 1 and "transport 'ros2' cannot start: rclpy cannot be imported" in lines[0], r.stderr
    assert "no ROS 2 on this machine" in lines[0] and "running without a transport" in lines[0]
    assert "steps:    50" in r.stdout and "ready:" not in r.stderr
    for extra in (["--transport", "ros2"], ["--paused"]):  # starts no ROS 2 nodes: refused
        r = subprocess.run([sys.executable, "-m", "sigcore", "run", str(WORLD), "--steps", "5", *extra],
                           capture_output=True, text=True, cwd=ROOT, timeout=120, env=env)
        assert r.returncode == 2 and "rclpy cannot be imported" in r.stderr + r.stdout, r.stderr


@pytest.mark.slow
def test_a_failing_controller_is_named_with_its_agent(tmp_path: Path) -> None:
    """A controller whose constructor raises is reported as that controller of that agent, located in the world
    file, exit 2; not as a backend that cannot build the world."""
    (tmp_path / "broken_controller.py").write_text(
        "from sigcore.agent import Controller\n\n\nclass Broken(Controller):\n"
        "    def __init__(self) -> None:\n        raise RuntimeError('no arm found')\n")
    r = subprocess.run([sys.executable, "-m", "sigcore", "run", str(WORLD), "--transport", "none", "--steps", "5",
                        "--controller", "moderator=broken_controller:Broken"], capture_output=True, text=True,
                       cwd=ROOT, timeout=120, env={**os.environ, "PYTHONPATH": str(tmp_path)})
    assert r.returncode == 2, r.stderr
    assert r.stderr.startswith(f"{WORLD}:")
    assert ("controller 'broken_controller:Broken' of agent 'moderator' raised RuntimeError while being created: "
            "no arm found") in r.stderr
    assert "backend" not in r.stderr and "Traceback" not in r.stderr


@pytest.mark.slow
def test_a_failing_feature_is_named(tmp_path: Path) -> None:
    """A feature (an installed plugin, found through its entry point) whose constructor raises is reported by name
    at its <plugin> line, exit 2; not as a backend that cannot build the world."""
    site = tmp_path / "site"
    info = site / "exploding_feature-0.1.dist-info"
    info.mkdir(parents=True)
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: exploding-feature\nVersion: 0.1\n")
    (info / "entry_points.txt").write_text("[sigcore]\nexploding = exploding_feature\n")
    (site / "exploding_feature.py").write_text(
        "from sigcore import hookimpl\nfrom sigcore.feature import Feature\n\n\n"
        "class Exploding(Feature):\n    name = 'exploding'\n\n"
        "    def __init__(self, sim, config):\n        raise RuntimeError('no GPU on this machine')\n\n\n"
        "@hookimpl\ndef sigcore_register_features(register):\n    register(Exploding)\n")
    world = tmp_path / "boom.xml"
    world.write_text('<world name="boom">\n  <object name="box" shape="box" size="0.1 0.1 0.1" pose="0 0 0.05"/>\n'
                     '  <plugin name="exploding"/>\n</world>\n')
    r = subprocess.run([sys.executable, "-m", "sigcore", "check", str(world)], capture_output=True, text=True,
                       cwd=ROOT, timeout=120, env={**os.environ, "PYTHONPATH": str(site)})
    assert r.returncode == 2, r.stderr
    assert (f"{world}:3: feature 'exploding' failed while being created: RuntimeError: no GPU on this machine"
            in r.stderr), r.stderr
    assert "backend" not in r.stderr and "Traceback" not in r.stderr


@pytest.mark.slow
def test_a_world_the_backend_cannot_build_is_reported_as_such(tmp_path: Path) -> None:
    """A mesh the engine cannot use (it passes the core's checks) is reported as the backend failing to build the
    world, at the entity's element (file:line:column), exit 2."""
    (tmp_path / "bad.obj").write_text("v 0 0 0\n" * 4 + "f 1 2 3\nf 1 2 4\n")  # all vertices in one point
    world = tmp_path / "w.xml"
    world.write_text('<world name="badmesh">\n  <object name="thing" mesh="bad.obj" pose="0 0 0.1"/>\n</world>\n')
    r = sigcore("check", str(world))
    assert r.returncode == 2 and f"{world}:2:3: cannot build the world with backend 'mujoco': object 'thing'" \
        in r.stderr
    assert "Traceback" not in r.stderr
