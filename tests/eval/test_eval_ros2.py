"""sigcore eval of the example ROS 2 solution (examples/cleanup/robot_node.py --lockstep, a separate rclpy process
per episode) over randomised episodes: locally with 2 workers, with a solution that crashes and one that hangs among
them, and the same episodes as tasks on a local Ray cluster bound to 127.0.0.1."""

from __future__ import annotations

import csv
import json
import os
import shutil
import socket
import subprocess
import sys
import tempfile
from collections.abc import Iterator
from pathlib import Path

import pytest

pytest.importorskip("rclpy")
pytest.importorskip("sigcore_msgs")

ROOT = Path(__file__).parent.parent.parent
WORLD = ROOT / "tests" / "data" / "eval" / "cleanup_one.xml"  # one trash item: an episode takes about 20 s here
NODE = f"{sys.executable} {ROOT / 'examples' / 'cleanup' / 'robot_node.py'} --lockstep"
# episode 0 (seed 0) hangs, episode 1 (seed 1) crashes, the others run the example node
SOLUTION = f'case "$SIGCORE_SEED" in 0) exec sleep 1000;; 1) sleep 1; exit 3;; *) exec {NODE};; esac'
TIMEOUT = 100  # a normal episode takes about 20 s alone, about 35 s beside another: the hang ends at 100 s
COMPARED = ("status", "success", "result", "score", "events")


def _rows(folder: Path) -> dict[int, dict[str, str]]:
    with open(folder / "episodes.csv", newline="") as f:
        return {int(row["episode"]): row for row in csv.DictReader(f)}


@pytest.fixture(scope="module")
def local(tmp_path_factory: pytest.TempPathFactory) -> dict:
    """6 episodes (seeds 0..5), 2 at once."""
    out = tmp_path_factory.mktemp("eval_local")
    r = subprocess.run([sys.executable, "-m", "sigcore", "eval", str(WORLD), "--solution", SOLUTION,
                        "--wait-for", "/robot_000/cmd_vel", "--episodes", "6", "--workers", "2",
                        "--timeout", str(TIMEOUT), "--out", str(out)], capture_output=True, text=True,
                       timeout=600, cwd=ROOT)
    return {"run": r, "out": out}


def test_the_example_solution_over_randomised_episodes(local: dict) -> None:
    """The 4 randomised episodes of the example node each score 1050 (grasp and box; succeeded), with their own
    seeds and ROS 2 domains; each has both logs and its results; the summary counts 4 of 6 succeeded and one failure
    of each kind."""
    r, out = local["run"], local["out"]
    assert r.returncode == 0, r.stdout[-3000:] + r.stderr[-3000:]
    rows = _rows(out)
    assert sorted(rows) == list(range(6))
    for i in range(2, 6):
        row = rows[i]
        assert (row["status"], row["result"], row["score"], row["success"]) == ("done", "succeeded", "1050.0",
                                                                                 "True"), row
        assert row["seed"] == str(i) and row["events"] == "grasp:1 correct_box:1 end:1"
        folder = Path(row["folder"])
        assert "lockstep: paused" in (folder / "solution.log").read_text()
        assert json.loads((folder / "result.json").read_text())["seed"] == i
    assert len({rows[i]["domain"] for i in range(6)}) >= 2  # episodes at once never share a domain
    summary = json.loads((out / "summary.json").read_text())
    assert summary["succeeded"] == 4 and summary["episodes"] == 6
    assert summary["failures"] == {"timeout": 1, "solution_crashed": 1, "simulator_error": 0}
    assert "success rate: 66.7 %" in r.stdout and "timed out 1, solution crashed 1" in r.stdout


def test_a_hanging_and_a_crashing_solution_are_recorded_as_such(local: dict) -> None:
    """The hanging solution's episode is killed at the timeout (its process group: no sleep is left); the
    crashing one is recorded with its exit code, and its simulator was stopped (SIGINT: it ends as it would on
    Ctrl-C, here while it was still starting)."""
    rows = _rows(local["out"])
    hang, crash = rows[0], rows[1]
    assert hang["status"] == "timeout" and float(hang["wall_time"]) >= TIMEOUT - 1, hang
    assert float(hang["wall_time"]) < TIMEOUT + 30
    assert crash["status"] == "solution_crashed" and crash["solution_exit"] == "3", crash
    assert "exited 3" in crash["reason"] and crash["sim_exit"] in ("", "0", "1", "130"), crash  # "": SIGINT
    # ended it before Python's handler was installed
    stray = subprocess.run(["pgrep", "-f", "exec sleep 1000|^sleep 1000"], capture_output=True, text=True)
    assert stray.stdout == "", stray.stdout


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


@pytest.fixture(scope="module")
def ray_cluster() -> Iterator[str]:
    """``ray start --head`` bound to 127.0.0.1 with 2 CPUs (2 episodes at once); stopped afterwards."""
    ray = shutil.which("ray", path=str(Path(sys.executable).parent))
    if ray is None:
        pytest.skip("Ray is not installed (scripts/setup.sh installs it)")
    port = _free_port()
    temp = tempfile.mkdtemp(prefix="ray", dir="/tmp")  # short: Ray's socket paths are limited to 107 bytes
    env = {**os.environ, "RAY_USAGE_STATS_ENABLED": "0", "RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER": "0"}  # stay on 127.0.0.1
    subprocess.run([ray, "start", "--head", "--node-ip-address=127.0.0.1", f"--port={port}", "--num-cpus=2",
                    "--include-dashboard=false", f"--temp-dir={temp}", "--disable-usage-stats"],
                   check=True, capture_output=True, timeout=120, env=env)
    try:
        yield f"127.0.0.1:{port}"
    finally:
        subprocess.run([ray, "stop", "--force"], capture_output=True, timeout=120, env=env)
        shutil.rmtree(temp, ignore_errors=True)


def test_the_same_episodes_on_a_local_ray_cluster_give_the_same_results(local: dict, ray_cluster: str,
                                                                           tmp_path: Path) -> None:
    """Episodes 2..5 (seeds 2..5) as Ray tasks of 1 CPU each: the same status, result, score and events as run here
    (simulated time within 2 s: the node pauses the simulation a few steps after it plays); their logs came back
    from the workers; every node of the cluster, as Ray lists them, has the address 127.0.0.1."""
    out = tmp_path / "ray"
    r = subprocess.run([sys.executable, "-m", "sigcore", "eval", str(WORLD), "--solution", SOLUTION,
                        "--wait-for", "/robot_000/cmd_vel", "--episodes", "4", "--seed", "2", "--timeout",
                        str(TIMEOUT), "--ray", ray_cluster, "--out", str(out)], capture_output=True, text=True,
                       timeout=600, cwd=ROOT)
    assert r.returncode == 0, r.stdout[-3000:] + r.stderr[-3000:]
    here, there = _rows(local["out"]), _rows(out)
    assert sorted(there) == [0, 1, 2, 3]
    for i, row in there.items():
        assert row["seed"] == str(i + 2)
        assert [row[k] for k in COMPARED] == [here[i + 2][k] for k in COMPARED], (row, here[i + 2])
        assert abs(float(row["sim_time"]) - float(here[i + 2]["sim_time"])) < 2.0
        assert "lockstep: paused" in (Path(row["folder"]) / "solution.log").read_text()
    nodes = json.loads((out / "summary.json").read_text())["nodes"]
    assert nodes and all(n["address"] == "127.0.0.1" for n in nodes), nodes
