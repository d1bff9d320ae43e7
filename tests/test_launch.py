"""launch/sigcore.launch.py: the command it runs is the tested CLI (launch itself is not installed here)."""

from __future__ import annotations

import importlib.util
import subprocess
import sys
from pathlib import Path
from types import ModuleType

import pytest

ROOT = Path(__file__).resolve().parent.parent
WORLD = ROOT / "tests" / "data" / "sim" / "world.xml"


def _launch_module() -> ModuleType:
    spec = importlib.util.spec_from_file_location("sigcore_launch", ROOT / "launch" / "sigcore.launch.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.mark.slow
def test_launch_command_runs_the_cli_for_real() -> None:
    """The launch file's command, with paused:=false and extra_args, runs sigcore run to its end (exit 0)."""
    cmd = _launch_module().sigcore_command(str(WORLD), "mujoco", "false", "--transport none --steps 50 -q",
                                           executable=str(Path(sys.executable).parent / "sigcore"))
    done = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert "steps:    50" in done.stdout and "backend 'mujoco'" in done.stdout


def test_launch_arguments_map_to_options() -> None:
    """backend, paused and extra_args become --backend, --paused and the split options, in that order."""
    cmd = _launch_module().sigcore_command("w.xml", "bullet", "True", "--factor 2 --ros-args -p 'sigros_agents:=a b'")
    assert cmd == ["sigcore", "run", "w.xml", "--backend", "bullet", "--paused", "--factor", "2", "--ros-args", "-p",
                   "sigros_agents:=a b"]


@pytest.mark.parametrize(("world", "paused", "match"), [("", "false", "'world' is required"),
                                                        ("w.xml", "maybe", "valid: true, false")])
def test_launch_arguments_are_checked(world: str, paused: str, match: str) -> None:
    """An empty world or a paused value that is not a boolean is refused, saying what is valid."""
    with pytest.raises(ValueError, match=match):
        _launch_module().sigcore_command(world, "mujoco", paused)


def test_package_xml_names_the_package_and_rclpy() -> None:
    """package.xml is format 3, package sigcore, ament_python, and depends on rclpy at run time."""
    import xml.etree.ElementTree as ET

    root = ET.parse(ROOT / "package.xml").getroot()
    assert root.get("format") == "3" and root.findtext("name") == "sigcore"
    assert root.findtext("export/build_type") == "ament_python"
    assert "rclpy" in [e.text for e in root.findall("exec_depend")]
