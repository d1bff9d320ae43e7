"""Overflowing numbers (issue 28, item 9): ``1e308``, ``inf`` and ``-1e308`` in every number attribute of the world
models are refused by ``sigcore check`` and ``sigcore run`` at the attribute's ``file:line:column``, naming it and
its valid range, never with a traceback; the largest valid values still run on both backends (and over ROS 2, where
``max_wheel_velocity="1e308"`` used to end the run with ``OverflowError``).

The worlds come from :mod:`hostile.overflow`; they are checked and run in one process per command
(``check_many.py``), so the imports are paid once.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
from pydantic import BaseModel

from hostile.overflow import AT_LIMIT, ATTRIBUTES, VALUES, OverflowCase, generate, generate_at_limit, number_fields
from hostile.test_hostile_worlds import _run_many
from sigcore.world import Camera, Drive, Gains, Gripper, Human, Lidar, NamedPose, Object, Robot, World
from sigcore.world.randomization import Option, RandomPose

MODELS: dict[str, type[BaseModel]] = {m.__name__: m for m in (World, Drive, Lidar, Camera, Gripper, Gains, Robot,
                                                                Object, Human, NamedPose, RandomPose, Option)}
"""Every model a world file's number attributes go into."""

_NOT_NUMBERS = {"World": {"seed"}}  # an integer: "1e308" is not one, and a huge integer seeds numpy as well
RUN_STEPS = ["--steps", "10", "--quiet", "--seed", "1"]  # --seed: <randomize> is drawn


@pytest.fixture(scope="module")
def cases(tmp_path_factory: pytest.TempPathFactory) -> list[OverflowCase]:
    """One world per number attribute and overflowing value."""
    return generate(tmp_path_factory.mktemp("overflow"))


def _located(case: OverflowCase, result: dict[str, Any]) -> str | None:
    """What is wrong with ``result`` for ``case`` (None: refused with exit 2 at the attribute, naming it)."""
    output = result["output"]
    if result["code"] != 2 or result["escaped"] or "Traceback" in output:
        return f"{case.name}: exit {result['code']}: {output[-400:]}"
    where = f"{case.path}:{case.line}:{case.column}:"
    says = "finite" if case.number == "inf" else "valid"  # inf: 'not a finite number'; 1e308: the valid range
    if where not in output or f"attribute '{case.attribute.attr}'" not in output or says not in output:
        return f"{case.name}: not located at {where} naming '{case.attribute.attr}' and '{says}': {output[:400]}"
    return None


def test_every_number_attribute_of_the_models_is_swept() -> None:
    """Each number field of each world model (floats, tuples of them, poses) has a row in ATTRIBUTES."""
    swept = {(a.model, a.field) for a in ATTRIBUTES}
    missing = [(name, f) for name, model in MODELS.items() for f in number_fields(model)
               if (name, f) not in swept and f not in _NOT_NUMBERS.get(name, set())]
    assert not missing
    assert len(swept) == len(ATTRIBUTES) >= 40


@pytest.mark.slow
def test_check_refuses_each_overflowing_number_at_its_attribute(cases: list[OverflowCase]) -> None:
    """`sigcore check` exits 2 on every world, at the attribute's file:line:column, naming it and the valid range
    (for inf: that the number must be finite)."""
    assert len(cases) == len(ATTRIBUTES) * len(VALUES)
    results, _ = _run_many(["check", "--transport", "none"], [c.path for c in cases])
    wrong = [why for c in cases if (why := _located(c, results[str(c.path)])) is not None]
    assert not wrong, "\n".join(wrong)


@pytest.mark.slow
@pytest.mark.parametrize("backend", ["mujoco", "bullet"])
def test_run_refuses_each_overflowing_number_without_a_traceback(cases: list[OverflowCase], backend: str) -> None:
    """`sigcore run --transport none --steps 10` on each backend exits 2 with the same located message, before
    anything runs (no traceback, no 'stopped by an error')."""
    results, _ = _run_many(["run", "--transport", "none", "--backend", backend, *RUN_STEPS], [c.path for c in cases])
    wrong = [why for c in cases if (why := _located(c, results[str(c.path)])) is not None]
    wrong += [c.name for c in cases if "stopped:  by an error" in results[str(c.path)]["output"]]
    assert not wrong, "\n".join(wrong)


@pytest.mark.ros2
def test_the_wheel_velocity_of_the_issue_is_refused_over_ros2(cases: list[OverflowCase]) -> None:
    """`sigcore run` with ROS 2 (where max_wheel_velocity="1e308" ended with OverflowError, exit 3) exits 2 at the
    attribute: 'valid: 0 < max_wheel_velocity <= 1000 [rad/s]'."""
    case = next(c for c in cases if c.name == "Drive_max_wheel_velocity_1e308")
    results, _ = _run_many(["run", "--transport", "ros2", *RUN_STEPS], [case.path], processes=1)
    result = results[str(case.path)]
    assert _located(case, result) is None, result["output"]
    assert "'1e308' is out of range; valid: 0 < max_wheel_velocity <= 1000 [rad/s]" in result["output"]


@pytest.mark.ros2
@pytest.mark.slow
def test_the_largest_valid_numbers_still_run(tmp_path: Path) -> None:
    """A world with each formerly unbounded attribute at its new limit passes check and runs 10 steps on MuJoCo and
    PyBullet (and over ROS 2 for the drive's wheel velocity, whose odometry covariance squares it) with exit 0."""
    worlds = generate_at_limit(tmp_path)
    assert len(worlds) == len(AT_LIMIT)
    wrong = []
    for command in (["check", "--transport", "none"], ["run", "--transport", "none", *RUN_STEPS],
                    ["run", "--transport", "none", "--backend", "bullet", *RUN_STEPS]):
        results, _ = _run_many(command, worlds)
        wrong += [f"{command[0]} {' '.join(command[1:5])} {Path(w).name}: exit {r['code']}: {r['output'][-300:]}"
                  for w, r in results.items() if r["code"] != 0 or r["escaped"] or "stopped:" in r["output"]]
    drive = [w for w in worlds if w.name == "Drive_max_wheel_velocity_limit.xml"]
    results, _ = _run_many(["run", "--transport", "ros2", *RUN_STEPS], drive, processes=1)
    wrong += [f"ros2 {Path(w).name}: exit {r['code']}: {r['output'][-300:]}" for w, r in results.items()
              if r["code"] != 0 or r["escaped"] or "stopped:" in r["output"]]
    assert not wrong, "\n".join(wrong)
