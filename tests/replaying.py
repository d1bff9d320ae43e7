"""Re-simulating a recording in a test: its world built again, the given inputs applied at their steps."""

from __future__ import annotations

from pathlib import Path

from sigcore.record.replay import Recording, compare, poses_now
from sigcore.sim import Simulation
from sigcore.sim.inputs import Input


def resimulate(rec: Recording, where: Path, inputs: list[Input], backend: str = "mujoco") -> tuple[bool, float, str]:
    """Run ``rec``'s world (written under ``where``) for as many steps as it recorded, applying ``inputs`` at their
    steps; then :func:`~sigcore.record.replay.compare` its last ground truth with the poses there."""
    again = Simulation(rec.world(where), backend)
    for _ in range(rec.final_step):
        for item in inputs:
            if item.step == again.step_count:
                again.inputs.apply(item)
        again.step()
    return compare(rec.truth[-1][1], poses_now(again))
