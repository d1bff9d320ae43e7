"""Replay does not depend on each transport remembering to log (issue 29, item 6): commands applied through the
core's verbs (``sim.inputs``: base velocity, spawn, message, entity state, entity information, delete) are noted by
the core, whichever client applied them, and ``sigcore replay`` reproduces the run bitwise."""

from __future__ import annotations

import ast
import re
import subprocess
import sys
from pathlib import Path

import pytest

from sigcore.record import Recorder
from sigcore.record.replay import load_recording
from sigcore.sim import Simulation
from sigcore.world import parse_world
from sigcore.world.resources import SpawnRequest

ROOT = Path(__file__).resolve().parents[2]
WORLD = ROOT / "tests" / "data" / "sim" / "world.xml"
STEPS = 600


class ScriptedClient:
    """A client of the core that is neither the ROS 2 transport nor the viewer: a script of commands by step."""

    def __init__(self, sim: Simulation) -> None:
        self.sim = sim

    def between_steps(self, step: int) -> None:
        inputs = self.sim.inputs
        if step == 20:
            inputs.base_velocity("bot", 0.4, 0.8)
        elif step == 60:
            [name] = inputs.spawn([SpawnRequest(resource='<object shape="box" size="0.1 0.1 0.1" mass="0.2"/>',
                                                name="crate", xyz=(1.0, -0.5, 0.4))], what="a crate")
            assert name == "crate"
        elif step == 100:
            inputs.message("moderator", "bot", "hello")
        elif step == 150:
            inputs.entity_state("cube", (0.3, 0.2, 0.6), (1.0, 0.0, 0.0, 0.0), (0.5, 0.0, 0.0), (0.0, 0.0, 2.0))
        elif step == 200:
            inputs.entity_info("heavy", "static_object", "a heavy box", ["furniture", "box"])
        elif step == 300:
            inputs.delete(["crate"])
        elif step == 400:
            inputs.wheel_velocity("bot", 0.0, 0.0)


@pytest.mark.slow
def test_a_client_of_the_core_verbs_is_recorded_and_replayed_bitwise(tmp_path: Path) -> None:
    sim = Simulation(parse_world(WORLD), "mujoco")
    recorder = Recorder(sim, tmp_path / "bag")
    client = ScriptedClient(sim)
    sim.start()
    for step in range(STEPS):
        client.between_steps(step)
        sim.step()
    sim.stop()
    recorder.close()
    rec = load_recording(tmp_path / "bag")
    assert [(i.step, i.kind) for i in rec.inputs] == [
        (20, "base_velocity"), (60, "spawn"), (100, "message"), (150, "entity_state"), (200, "entity_info"),
        (300, "delete"), (400, "wheel_velocity")]
    out = subprocess.run([sys.executable, "-m", "sigcore", "replay", str(tmp_path / "bag"), "-q"],
                         capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, out.stdout + out.stderr
    text = " ".join(out.stdout.split())
    assert "7 commands applied (of 7 recorded)" in text, out.stdout
    assert re.search(r"ground truth: all \d+ recorded messages \(steps 0 to 600\) bitwise equal", text), out.stdout


def test_no_plugin_notes_inputs_itself() -> None:
    """Only the core notes inputs: no bundled plugin calls ``inputs.note`` or ``inputs.note_spawn`` (it applies
    commands through the verbs of ``sim.inputs``, which note them)."""
    calls = []
    for path in sorted((ROOT / "plugins").rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            if isinstance(node, ast.Attribute) and node.attr in ("note", "note_spawn") and \
                    isinstance(node.value, ast.Attribute) and node.value.attr == "inputs":
                calls.append(f"{path.relative_to(ROOT)}:{node.lineno}")
    assert calls == []
