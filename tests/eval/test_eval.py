"""sigcore eval without ROS 2: the summary's statistics, the episode log, in-process controllers over seeded episodes
(the same seeds, the same results), an interrupted evaluation resumed, refusals, the domain range, --min-success and
the ETA."""

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

from sigcore.eval import (
    ENV,
    EpisodeLog,
    EpisodeRow,
    Eta,
    EvalError,
    Settings,
    mean_interval,
    parse_domains,
    prepare,
    summarize,
    wilson,
)
from sigcore.eval.domains import DomainLease

pytestmark = pytest.mark.slow

ROOT = Path(__file__).parent.parent.parent
WORLD = ROOT / "worlds" / "cleanup_random.xml"
SIGCORE = [sys.executable, "-m", "sigcore"]


def _eval(*args: str, timeout: float = 300, env: dict[str, str] | None = None) -> subprocess.CompletedProcess[str]:
    return subprocess.run([*SIGCORE, "eval", *args], capture_output=True, text=True, timeout=timeout, cwd=ROOT,
                          env={**os.environ, **(env or {})})


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
    """Rows written to episodes.csv read back equal; the summary counts successes, failures by kind and results;
    every interval is {low, high}; the score's mean, median, min and max leave out (and count) the episodes that never
    left t = 0 (not started, or crashed before) and those without a score, while the success rate counts them all."""
    rows = [EpisodeRow(0, 0, "done", True, "succeeded", 3150.0, "grasp:3", 90.0, 40.0, 0, 0, 120),
            EpisodeRow(1, 1, "timeout", False, "running", 1050.0, "grasp:1", 30.0, 60.0, None, None, 121,
                       reason="not ended"),
            EpisodeRow(2, 2, "solution_crashed", False, "running", 0.0, "", 2.0, 3.0, 0, 3, 122),
            EpisodeRow(3, 3, "simulator_error", False, "", None, "", None, 1.0, 2, None, 123),
            EpisodeRow(4, 4, "not_started", False, "running", 0.0, "", 0.0, 600.0, 0, None, 124),
            EpisodeRow(5, 5, "solution_crashed", False, "running", 0.0, "", 0.0, 2.0, 0, 1, 125)]
    log = EpisodeLog(tmp_path)
    for row in rows:
        log.append(row)
    assert log.read() == rows
    s = summarize(log.read(), 7)
    assert s["episodes"] == 6 and s["planned"] == 7 and s["succeeded"] == 1 and s["success_rate"] == 1 / 6
    assert s["failures"] == {"timeout": 1, "not_started": 1, "solution_crashed": 2, "simulator_error": 1}
    assert s["results"] == {"succeeded": 1, "running": 4}
    assert s["scored_episodes"] == 3 and s["score_mean"] == pytest.approx((3150 + 1050) / 3)
    assert s["score_excluded"] == {"never_ran": 2, "no_score": 1}
    assert (s["score_median"], s["score_min"], s["score_max"]) == (1050.0, 0.0, 3150.0)
    half = 4.303 * math.sqrt(((3150 - 1400) ** 2 + (1050 - 1400) ** 2 + 1400 ** 2) / 2) / math.sqrt(3)
    assert s["score_interval_95"] == {"low": pytest.approx(1400 - half), "high": pytest.approx(1400 + half)}
    low, high = wilson(1, 6)
    assert s["success_interval_95"] == {"low": low, "high": high}
    assert s["sim_time_mean"] == pytest.approx((90 + 30 + 2) / 3)  # the ones that ran


def test_a_folder_of_another_evaluation_is_refused(tmp_path: Path) -> None:
    """A folder holding episodes is refused without --resume; with --resume, other settings are refused by name."""
    settings = Settings(str(WORLD), 3, 0, None, ("robot_000=cleanup.robot",), "mujoco", 60.0, ("--fast",), (), ".")
    assert prepare(tmp_path, settings, resume=False) == []
    EpisodeLog(tmp_path).append(EpisodeRow(0, 0, "done", True))
    with pytest.raises(EvalError, match="holds 1 episode of.*--resume"):
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
    assert summary["succeeded"] == 2 and summary["success_interval_95"]["high"] == 1.0
    assert summary["settings"]["seed"] == 11
    for row in runs[0]:
        result = json.loads((Path(row["folder"]) / "result.json").read_text())
        assert result["seed"] == int(row["seed"]) and result["features"]["referee"]["events"][-1]["kind"] == "end"


def test_an_interrupted_evaluation_resumes(tmp_path: Path) -> None:
    """Ctrl-C after the first episode: exit 130, the recorded row kept, --resume named; --resume then runs only the
    missing episodes, and the first row is unchanged (episodes of 5 simulated seconds: the task need not end)."""
    out = tmp_path / "run"
    args = [str(WORLD), "--controller", "robot_000=cleanup.robot", "--episodes", "3", "--duration", "5", "--out",
            str(out)]
    # SIGINT as a terminal gives it, even where this test runs in a background job (which inherits SIGINT ignored)
    proc = subprocess.Popen([*SIGCORE, "eval", *args], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            cwd=ROOT, start_new_session=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
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


def test_domain_ranges_are_read_and_bad_ones_refused() -> None:
    """LOW-HIGH (both included) and N are read; a range outside 0-232, LOW above HIGH or another form is refused,
    naming the valid form."""
    assert parse_domains("120-232") == range(120, 233)
    assert parse_domains(" 40 - 49 ") == range(40, 50)
    assert parse_domains("0") == range(0, 1)
    for bad, why in (("200-233", "above 232"), ("9-3", "LOW 9 is above HIGH 3"), ("a-b", "not a range"),
                     ("-1", "not a range"), ("1-2-3", "not a range"), ("", "not a range")):
        with pytest.raises(EvalError, match=why) as e:
            parse_domains(bad)
        assert "valid: LOW-HIGH with 0 <= LOW <= HIGH <= 232" in str(e.value)


def test_leases_take_distinct_domains_of_their_range(tmp_path: Path) -> None:
    """Two leases of a range of two domains hold both, one each; a lease of one domain gets it when it is free."""
    with DomainLease(range(7, 9), tmp_path) as a, DomainLease(range(7, 9), tmp_path) as b:
        assert {a, b} == {7, 8}
    with DomainLease(range(8, 9), tmp_path) as c:
        assert c == 8


def test_the_domain_option_wins_over_the_environment_variable(tmp_path: Path) -> None:
    """--domains gives the episodes' domains, else SIGCORE_EVAL_DOMAINS does (read back from episodes.csv); a bad
    one of either is refused (exit 2) naming where it came from and the valid form."""
    base = [str(WORLD), "--controller", "robot_000=cleanup.robot", "--duration", "0.5", "--episodes", "2",
            "--workers", "2"]
    r = _eval(*base, "--domains", "225-226", "--out", str(tmp_path / "option"), env={ENV: "7-8"})
    assert r.returncode == 0, r.stdout + r.stderr
    assert sorted(int(row["domain"]) for row in _rows(tmp_path / "option")) == [225, 226]
    r = _eval(*base, "--out", str(tmp_path / "env"), env={ENV: "227-228"})
    assert r.returncode == 0, r.stdout + r.stderr
    assert sorted(int(row["domain"]) for row in _rows(tmp_path / "env")) == [227, 228]
    assert json.loads((tmp_path / "env" / "eval.json").read_text())["domains"] == [227, 228]
    r = _eval(*base, "--domains", "300", "--out", str(tmp_path / "bad"))
    assert r.returncode == 2 and "--domains '300': domain 300 is above 232" in r.stderr, r.stderr
    r = _eval(*base, "--out", str(tmp_path / "bad"), env={ENV: "1..5"})
    assert r.returncode == 2 and f"{ENV} '1..5' is not a range" in r.stderr and "LOW-HIGH" in r.stderr, r.stderr
    assert not (tmp_path / "bad").exists()


def test_min_success_gates_the_exit_code(tmp_path: Path) -> None:
    """--min-success 0.5: exit 1 when fewer succeed (0 of 1: the task cut at 1 simulated second), exit 0 when enough
    do (1 of 1: the scripted controller's whole task); without it, 0 % still exits 0; a rate outside 0-1 is refused.
    One episode is written "1 episode", never "1 episodes"."""
    base = [str(WORLD), "--controller", "robot_000=cleanup.robot", "--episodes", "1"]
    r = _eval(*base, "--duration", "1", "--min-success", "0.5", "--out", str(tmp_path / "few"))
    assert r.returncode == 1, r.stdout + r.stderr
    assert "success rate: 0.0 %" in r.stdout and "below --min-success 0.5 (50 %): exit 1" in r.stderr, r.stderr
    assert "1 episode with a score" in r.stdout and "1 episodes" not in r.stdout + r.stderr
    r = _eval(*base, "--duration", "1", "--out", str(tmp_path / "ungated"))
    assert r.returncode == 0, r.stdout + r.stderr
    r = _eval(*base, "--min-success", "0.5", "--out", str(tmp_path / "enough"))
    assert r.returncode == 0, r.stdout + r.stderr
    assert "success rate: 100.0 %" in r.stdout and "at least --min-success 0.5: exit 0" in r.stderr
    r = _eval(*base, "--min-success", "50", "--out", str(tmp_path / "bad"))
    assert r.returncode == 2 and "--min-success 50: a success rate is a fraction; valid: 0 to 1" in r.stderr


def test_an_episode_still_running_at_the_timeout_is_timed_out(tmp_path: Path) -> None:
    """The scripted controller paced at real time (a task of about 90 simulated seconds) with --timeout 30: the
    episode is stopped and recorded as `timeout`, not `not_started` (it had left t = 0: its results say so); the
    console names its logs."""
    r = _eval(str(WORLD), "--controller", "robot_000=cleanup.robot", "--factor", "1", "--timeout", "30",
              "--episodes", "1", "--out", str(tmp_path))
    assert r.returncode == 0, r.stdout + r.stderr
    (row,) = _rows(tmp_path)
    assert row["status"] == "timeout" and float(row["sim_time"]) > 0, row
    assert "not ended within 30 s" in row["reason"]
    assert f"logs: {tmp_path / 'episodes' / '0000'}" in r.stderr
    assert "sigcore eval: stopped the simulator (SIGTERM)" in (tmp_path / "episodes" / "0000" / "sim.log").read_text()


def test_the_eta_counts_the_workers() -> None:
    """4 episodes of 100 s on 2 workers: when the first 2 end at 100 s, 100 s are left (not 3 x 100 s, as if one ran
    at a time); the ETA then counts down with the clock, and is 0 once all have ended."""
    now = [0.0]
    eta = Eta(4, 2, clock=lambda: now[0])
    assert eta.left() is None
    now[0] = 100.0
    eta.ended(100.0)
    assert eta.left() == pytest.approx(100.0)
    eta.ended(100.0)
    assert eta.left() == pytest.approx(100.0)
    now[0] = 150.0
    assert eta.left() == pytest.approx(50.0)
    now[0] = 200.0
    eta.ended(100.0)
    eta.ended(100.0)
    assert eta.left() == 0.0
    one = Eta(3, 1, clock=lambda: now[0])
    now[0] = 260.0
    one.ended(60.0)
    assert one.left() == pytest.approx(120.0)
    late = Eta(2, 4, clock=lambda: now[0])  # more workers than episodes
    late.set_workers(8)
    now[0] = 300.0
    late.ended(40.0)
    assert late.left() == pytest.approx(0.0)
