"""sigcore eval without ROS 2: the summary's statistics, the episode log, in-process controllers over seeded episodes
(the same seeds, the same results), an interrupted evaluation resumed, refusals."""

from __future__ import annotations

import csv
import json
import math
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from sigcore.eval import EpisodeLog, EpisodeRow, EvalError, Settings, mean_interval, prepare, summarize, wilson

ROOT = Path(__file__).parent.parent.parent
WORLD = ROOT / "worlds" / "cleanup_random.xml"
SIGCORE = [sys.executable, "-m", "sigcore"]


def _eval(*args: str, timeout: float = 300) -> subprocess.CompletedProcess[str]:
    return subprocess.run([*SIGCORE, "eval", *args], capture_output=True, text=True, timeout=timeout, cwd=ROOT)


def _rows(folder: Path) -> list[dict[str, str]]:
    with open(folder / "episodes.csv", newline="") as f:
        return list(csv.DictReader(f))


def test_wilson_interval_matches_known_values() -> None:
    """The Wilson 95 % interval: 0 of 10 gives (0, 0.278), 10 of 10 (0.722, 1), 5 of 10 (0.237, 0.763)."""
    assert wilson(0, 10) == (0.0, pytest.approx(0.2775, abs=1e-3))
    low, high = wilson(10, 10)
    assert low == pytest.approx(0.7225, abs=1e-3) and high == 1.0
    low, high = wilson(5, 10)
    assert (low, high) == (pytest.approx(0.2366, abs=1e-3), pytest.approx(0.7634, abs=1e-3))
    assert wilson(0, 0) == (0.0, 1.0)


def test_mean_interval_uses_students_t() -> None:
    """Mean ± t(0.975, n-1) s / sqrt(n): for 1, 2, 3 (s = 1, n = 3) the half-width is 4.303 / sqrt(3)."""
    mean, half = mean_interval([1.0, 2.0, 3.0])  # type: ignore[misc]
    assert mean == 2.0 and half == pytest.approx(4.303 / math.sqrt(3))
    assert mean_interval([5.0]) == (5.0, 0.0)
    assert mean_interval([]) is None


def test_the_summary_counts_failures_by_kind(tmp_path: Path) -> None:
    """Rows written to episodes.csv read back equal; the summary counts successes, failures by kind and results."""
    rows = [EpisodeRow(0, 0, "done", True, "succeeded", 3150.0, "grasp:3", 90.0, 40.0, 0, 0, 120),
            EpisodeRow(1, 1, "timeout", False, "running", 1050.0, "grasp:1", 30.0, 60.0, None, None, 121,
                       reason="not ended"),
            EpisodeRow(2, 2, "solution_crashed", False, "running", 0.0, "", 2.0, 3.0, 0, 3, 122),
            EpisodeRow(3, 3, "simulator_error", False, "", None, "", None, 1.0, 2, None, 123)]
    log = EpisodeLog(tmp_path)
    for row in rows:
        log.append(row)
    assert log.read() == rows
    s = summarize(log.read(), 5)
    assert s["episodes"] == 4 and s["planned"] == 5 and s["succeeded"] == 1 and s["success_rate"] == 0.25
    assert s["failures"] == {"timeout": 1, "solution_crashed": 1, "simulator_error": 1}
    assert s["results"] == {"succeeded": 1, "running": 2}
    assert s["scored_episodes"] == 3 and s["score_mean"] == pytest.approx((3150 + 1050) / 3)


def test_a_folder_of_another_evaluation_is_refused(tmp_path: Path) -> None:
    """A folder holding episodes is refused without --resume; with --resume, other settings are refused by name."""
    settings = Settings(str(WORLD), 3, 0, None, ("robot_000=cleanup.robot",), "mujoco", 60.0, ("--fast",), (), ".")
    assert prepare(tmp_path, settings, resume=False) == []
    EpisodeLog(tmp_path).append(EpisodeRow(0, 0, "done", True))
    with pytest.raises(EvalError, match="holds 1 episodes.*--resume"):
        prepare(tmp_path, settings, resume=False)
    other = Settings(str(WORLD), 3, 7, None, ("robot_000=cleanup.robot",), "mujoco", 60.0, ("--fast",), (), ".")
    with pytest.raises(EvalError, match="seed: 0 then, 7 now"):
        prepare(tmp_path, other, resume=True)
    assert len(prepare(tmp_path, settings, resume=True)) == 1


def test_controller_episodes_with_the_same_seeds_give_the_same_results(tmp_path: Path) -> None:
    """The scripted controller over 2 seeded episodes, 2 at once, twice: the same rows (score, result, events and
    simulated time, to the step) and different layouts for the two seeds (their result files differ in the robot's
    start); the summary says 2 of 2 succeeded."""
    runs = []
    for name in ("a", "b"):
        r = _eval(str(WORLD), "--controller", "robot_000=cleanup.robot", "--episodes", "2", "--seed", "11",
                  "--workers", "2", "--out", str(tmp_path / name))
        assert r.returncode == 0, r.stdout + r.stderr
        assert "success rate: 100.0 %" in r.stdout, r.stdout
        runs.append(sorted(_rows(tmp_path / name), key=lambda row: int(row["episode"])))
    keys = ("episode", "seed", "status", "success", "result", "score", "events", "sim_time")
    assert [[row[k] for k in keys] for row in runs[0]] == [[row[k] for k in keys] for row in runs[1]]
    assert [row["seed"] for row in runs[0]] == ["11", "12"]
    assert all(row["result"] == "succeeded" and row["score"] == "3150.0" for row in runs[0])
    summary = json.loads((tmp_path / "a" / "summary.json").read_text())
    assert summary["succeeded"] == 2 and summary["success_interval_95"][1] == 1.0
    assert summary["settings"]["seed"] == 11
    for row in runs[0]:
        result = json.loads((Path(row["folder"]) / "result.json").read_text())
        assert result["seed"] == int(row["seed"]) and result["features"]["referee"]["events"][-1]["kind"] == "end"


def test_an_interrupted_evaluation_resumes(tmp_path: Path) -> None:
    """Ctrl-C after the first episode: exit 130, the recorded row kept, --resume named; --resume then runs only the
    missing episodes, and the first row is unchanged."""
    out = tmp_path / "run"
    args = [str(WORLD), "--controller", "robot_000=cleanup.robot", "--episodes", "3", "--out", str(out)]
    proc = subprocess.Popen([*SIGCORE, "eval", *args], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            cwd=ROOT, start_new_session=True)
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and not (out / "episodes.csv").exists():
        time.sleep(0.1)
    assert (out / "episodes.csv").exists()
    os.killpg(proc.pid, signal.SIGINT)
    stdout, stderr = proc.communicate(timeout=60)
    assert proc.returncode == 130, stdout + stderr
    assert "--resume" in stderr
    first = _rows(out)
    assert 1 <= len(first) < 3
    r = _eval(*args, "--resume")
    assert r.returncode == 0, r.stdout + r.stderr
    rows = _rows(out)
    assert sorted(int(row["episode"]) for row in rows) == [0, 1, 2]
    assert rows[:len(first)] == first
    assert f"{3 - len(first)} of 3 episodes to run ({len(first)} recorded)" in r.stderr


def test_bad_settings_are_refused_with_what_is_valid(tmp_path: Path) -> None:
    """Neither --solution nor --controller, --fast with --factor, a folder of episodes without --resume: exit 2."""
    r = _eval(str(WORLD), "--out", str(tmp_path / "x"))
    assert r.returncode == 2 and "--solution 'COMMAND'" in r.stderr and "--controller" in r.stderr
    r = _eval(str(WORLD), "--controller", "robot_000=cleanup.robot", "--fast", "--factor", "2")
    assert r.returncode == 2 and "exclude each other" in r.stderr
    EpisodeLog(tmp_path).append(EpisodeRow(0, 0, "done", True))
    r = _eval(str(WORLD), "--controller", "robot_000=cleanup.robot", "--out", str(tmp_path))
    assert r.returncode == 2 and "--resume to go on" in r.stderr
