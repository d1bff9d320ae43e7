"""sigcore eval of the example ROS 2 solution (examples/cleanup/robot_node.py --lockstep, a separate rclpy process
per episode) over randomised episodes: locally with 2 workers in a given range of ROS 2 domains, with a solution that
crashes among them, and the same episodes as tasks on a local Ray cluster bound to 127.0.0.1; a solution that never
starts the simulation; a solution that dies at once."""

from __future__ import annotations

import csv
import json
import os
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
from collections.abc import Iterator
from pathlib import Path

import pytest

pytestmark = [pytest.mark.ros2, pytest.mark.slow]

pytest.importorskip("rclpy")
pytest.importorskip("sigcore_msgs")

ROOT = Path(__file__).parent.parent.parent
WORLD = ROOT / "tests" / "data" / "eval" / "cleanup_one.xml"  # one trash item: an episode takes about 20 s here
NODE = f"{sys.executable} {ROOT / 'examples' / 'cleanup' / 'robot_node.py'} --lockstep"
# each says its domain; seed 1 crashes, the others run the example node
SOLUTION = f'echo "ROS_DOMAIN_ID=$ROS_DOMAIN_ID"; case "$SIGCORE_SEED" in 1) sleep 1; exit 3;; *) exec {NODE};; esac'
SEEDS = (1, 2, 3)
"""The local episodes' seeds: 1 crashes, 2 and 3 run the example node."""
TIMEOUT = 150  # a bound only: a normal episode takes about 20 s alone, about 35 s beside another (65 s on a loaded
# machine)
HANG_TIMEOUT = 20  # the solution that never starts the simulation is stopped then
SIM_TIME_MARGIN = 10.0  # [s] the simulation runs at real time from its start until the node takes it in lockstep:
# 2.2 s apart once on a loaded machine (load average 18 on 2 cores)
RAY_TIMEOUT = 400  # no episode hangs on Ray: a margin for a loaded machine costs nothing there
DOMAINS = range(229, 232)  # --domains 229-231 here; 226-228 (SIGCORE_EVAL_DOMAINS) on Ray
COMPARED = ("status", "success", "result", "score", "events")


def _eval(*args: str, env: dict[str, str] | None = None) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "sigcore", "eval", *args], capture_output=True, text=True,
                          timeout=600, cwd=ROOT, env={**os.environ, **(env or {})})


def _rows(folder: Path) -> dict[int, dict[str, str]]:
    with open(folder / "episodes.csv", newline="") as f:
        return {int(row["episode"]): row for row in csv.DictReader(f)}


@pytest.fixture(scope="module")
def local(tmp_path_factory: pytest.TempPathFactory) -> dict:
    """3 episodes (seeds 1..3), 2 at once, in domains 229-231."""
    out = tmp_path_factory.mktemp("eval_local")
    r = _eval(str(WORLD), "--solution", SOLUTION, "--wait-for", "/robot_000/cmd_vel", "--episodes", str(len(SEEDS)),
              "--seed", str(SEEDS[0]), "--workers", "2", "--timeout", str(TIMEOUT), "--domains", "229-231", "--out",
              str(out))
    return {"run": r, "out": out}


def test_the_example_solution_over_randomised_episodes(local: dict) -> None:
    """The 2 randomised episodes of the example node each score 1050 (grasp and box; succeeded), with their own
    seeds and ROS 2 domains; each has both logs and its results; the summary counts 2 of 3 succeeded and the crash."""
    r, out = local["run"], local["out"]
    assert r.returncode == 0, r.stdout[-3000:] + r.stderr[-3000:]
    rows = _rows(out)
    assert sorted(rows) == list(range(len(SEEDS)))
    for i in (1, 2):
        row = rows[i]
        assert (row["status"], row["result"], row["score"], row["success"]) == ("done", "succeeded", "1050.0",
                                                                                 "True"), row
        assert row["seed"] == str(SEEDS[i]) and row["events"] == "grasp:1 correct_box:1 end:1"
        folder = Path(row["folder"])
        assert "lockstep: paused" in (folder / "solution.log").read_text()
        assert json.loads((folder / "result.json").read_text())["seed"] == SEEDS[i]
    assert len({row["domain"] for row in rows.values()}) >= 2  # episodes at once never share a domain
    summary = json.loads((out / "summary.json").read_text())
    assert summary["succeeded"] == 2 and summary["episodes"] == 3
    assert summary["failures"] == {"timeout": 0, "not_started": 0, "solution_crashed": 1, "simulator_error": 0}
    assert "success rate: 66.7 %" in r.stdout and "timed out 0, not started 0, solution crashed 1" in r.stdout


def test_each_episode_takes_its_domain_from_the_given_range(local: dict) -> None:
    """--domains 229-231: every episode's domain (episodes.csv) is in the range, and is the ROS_DOMAIN_ID its
    solution saw; the simulator was in it too (the example node's episodes played: their --wait-for saw the node)."""
    rows = _rows(local["out"])
    for row in rows.values():
        assert int(row["domain"]) in DOMAINS, row
        seen = (Path(row["folder"]) / "solution.log").read_text().splitlines()[0]
        assert seen == f"ROS_DOMAIN_ID={row['domain']}", (seen, row)
    assert all(float(rows[i]["sim_time"]) > 0 for i in (1, 2))
    assert "ROS 2 domains 229-231" in local["run"].stderr


def test_a_crashing_solution_is_recorded_and_left_out_of_the_mean(local: dict) -> None:
    """The crashing solution is recorded with its exit code, and its simulator was stopped; the mean score is of the
    two episodes that ran (the crash came while the simulator started or waited at t = 0 for its peers)."""
    r, rows = local["run"], _rows(local["out"])
    crash = rows[0]
    assert crash["status"] == "solution_crashed" and crash["solution_exit"] == "3", crash
    assert "exited 3" in crash["reason"] and crash["sim_exit"] in ("", "0", "1"), crash  # "": ended by SIGTERM
    summary = json.loads((local["out"] / "summary.json").read_text())
    assert summary["scored_episodes"] == 2 and summary["score_mean"] == 1050.0, summary
    assert f"logs: {crash['folder']}" in r.stderr


def test_a_simulation_that_never_started_is_reported_as_such(tmp_path: Path) -> None:
    """A solution that never makes the awaited topic's peers: its episode is stopped at the timeout as
    `not_started` (the simulation still at t = 0, the --wait-for topic named), its process group killed (no sleep is
    left), and its score of 0 is left out of the mean score, which says so."""
    r = _eval(str(WORLD), "--solution", "exec sleep 1000", "--wait-for", "/robot_000/cmd_vel", "--episodes", "1",
              "--timeout", str(HANG_TIMEOUT), "--domains", "229-231", "--out", str(tmp_path))
    assert r.returncode == 0, r.stdout[-3000:] + r.stderr[-3000:]
    hang = _rows(tmp_path)[0]
    assert hang["status"] == "not_started" and hang["sim_time"] == "0.0", hang
    assert "still at t = 0" in hang["reason"] and "--wait-for /robot_000/cmd_vel" in hang["reason"], hang
    assert HANG_TIMEOUT - 1 <= float(hang["wall_time"]) < HANG_TIMEOUT + 30, hang
    stray = subprocess.run(["pgrep", "-f", "^sleep 1000"], capture_output=True, text=True)
    assert stray.stdout == "", stray.stdout
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["failures"]["not_started"] == 1 and summary["score_excluded"]["never_ran"] == 1, summary
    assert "not in score: " in r.stdout and "that never left t = 0" in r.stdout, r.stdout
    assert f"logs: {hang['folder']}" in r.stderr


def test_a_solution_that_dies_at_once_leaves_clean_logs(tmp_path: Path) -> None:
    """A solution that exits 3 at once, while its simulator is still starting: sim.log holds no traceback but one
    line saying why and how the simulator was stopped; the console names where the logs are."""
    r = _eval(str(WORLD), "--solution", "exit 3", "--wait-for", "/robot_000/cmd_vel", "--episodes", "2", "--workers",
              "2", "--out", str(tmp_path))
    assert r.returncode == 0, r.stdout + r.stderr
    for i, row in _rows(tmp_path).items():
        assert row["status"] == "solution_crashed" and row["solution_exit"] == "3", row
        log = (Path(row["folder"]) / "sim.log").read_text()
        assert "Traceback" not in log and "KeyboardInterrupt" not in log, log
        assert "sigcore eval: stopped the simulator (SIGTERM)" in log and "the solution exited 3" in log, log
        assert f"logs: {tmp_path / 'episodes' / f'{i:04d}'}" in r.stderr
    assert f"logs:         {tmp_path / 'episodes'}/NNNN/" in r.stdout


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


@pytest.fixture(scope="module")
def ray_cluster() -> Iterator[str]:
    """``ray start --head`` bound to 127.0.0.1 with 2 CPUs (2 episodes at once), in a process group of its own that
    is killed afterwards (``ray stop`` would stop every Ray cluster on the machine: a bench's or another test's)."""
    ray = shutil.which("ray", path=str(Path(sys.executable).parent))
    if ray is None:
        pytest.skip("Ray is not installed (scripts/setup.sh installs it)")
    port = _free_port()
    temp = tempfile.mkdtemp(prefix="ray", dir="/tmp")  # short: Ray's socket paths are limited to 107 bytes
    env = {**os.environ, "RAY_USAGE_STATS_ENABLED": "0", "RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER": "0"}  # stay on 127.0.0.1
    start = subprocess.Popen([ray, "start", "--head", "--node-ip-address=127.0.0.1", f"--port={port}", "--num-cpus=2",
                              "--include-dashboard=false", f"--temp-dir={temp}", "--disable-usage-stats"],
                             stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, env=env,
                             start_new_session=True)
    try:
        said, _ = start.communicate(timeout=120)
        assert start.returncode == 0, f"ray start failed ({start.returncode}):\n{said[-3000:]}"
        yield f"127.0.0.1:{port}"
    finally:
        try:
            os.killpg(start.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
        shutil.rmtree(temp, ignore_errors=True)


def test_the_same_episodes_on_a_local_ray_cluster_give_the_same_results(local: dict, ray_cluster: str,
                                                                           tmp_path: Path) -> None:
    """The example node's episodes (seeds 2 and 3) as Ray tasks of 1 CPU each: the same status, result, score and
    events as run here (simulated time within SIM_TIME_MARGIN: the node pauses the simulation some steps after it
    plays); their logs came back from the workers; their domains are of SIGCORE_EVAL_DOMAINS; every node of the
    cluster, as Ray lists them, has the address 127.0.0.1."""
    out = tmp_path / "ray"
    r = _eval(str(WORLD), "--solution", SOLUTION, "--wait-for", "/robot_000/cmd_vel", "--episodes", "2", "--seed", "2",
              "--timeout", str(RAY_TIMEOUT), "--ray", ray_cluster, "--out", str(out),
              env={"SIGCORE_EVAL_DOMAINS": "226-228"})
    assert r.returncode == 0, r.stdout[-3000:] + r.stderr[-3000:]
    here = {row["seed"]: row for row in _rows(local["out"]).values()}
    there = _rows(out)
    assert sorted(there) == [0, 1]
    for i, row in there.items():
        assert row["seed"] == str(i + 2)
        assert [row[k] for k in COMPARED] == [here[row["seed"]][k] for k in COMPARED], (row, here[row["seed"]])
        assert abs(float(row["sim_time"]) - float(here[row["seed"]]["sim_time"])) < SIM_TIME_MARGIN
        assert "lockstep: paused" in (Path(row["folder"]) / "solution.log").read_text()
        assert 226 <= int(row["domain"]) <= 228, row
    nodes = json.loads((out / "summary.json").read_text())["nodes"]
    assert nodes and all(n["address"] == "127.0.0.1" for n in nodes), nodes
