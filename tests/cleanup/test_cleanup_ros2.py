"""The clean-up task end to end over real ROS 2: simulator, robot node and moderator node as separate processes."""

from __future__ import annotations

import json
import re
import subprocess
import sys
from pathlib import Path

import pytest

pytest.importorskip("rclpy")
pytest.importorskip("sigcore_msgs")

ROOT = Path(__file__).parent.parent.parent


def test_cleanup_task_over_ros2_scores_every_item(tmp_path: Path) -> None:
    """examples/cleanup/run_task.py exits 0; the referee scores 3 grasps and 3 correct boxes (3150), no penalty;
    the moderator node received /referee/score, /referee/events and /referee/result, which agree with the printed
    score table."""
    log = tmp_path / "referee.json"
    r = subprocess.run([sys.executable, str(ROOT / "examples" / "cleanup" / "run_task.py"), "--timeout", "200",
                        "--referee-log", str(log)], capture_output=True, text=True, timeout=260, cwd=ROOT)
    out = r.stdout
    assert r.returncode == 0, out[-3000:] + r.stderr[-3000:]
    assert "succeeded" in out and "score 3150" in out
    assert sorted(re.findall(r"correct_box\s+\+1000\s+\d+\s+(\w+) in (\w+)", out)) == [
        ("apple_2", "trashbox_1"), ("can_0", "trashbox_2"), ("petbottle_1", "trashbox_0")]
    assert len(re.findall(r"\bgrasp\s+\+50", out)) == 3
    assert not re.search(r"\b(collision|wrong_box)\s+-", out)
    assert "robot_000 grasped can_0" in out
    _check_referee_topics(json.loads(log.read_text()), out)


def _check_referee_topics(got: dict, out: str) -> None:
    """The referee's topics as the moderator node received them agree with the score table ``sigcore run`` printed."""
    table = re.findall(r"^\s+(\d+\.\d\d)\s+(\w+)\s+([+-]\d+)\s+(-?\d+)\s+(.*)$", out, re.MULTILINE)
    assert table, out[-3000:]
    events = got["events"]
    assert [(f"{e['time']:.2f}", e["kind"], f"{e['points']:+d}", str(e["score"]), e["text"]) for e in events] == \
        [tuple(row) for row in table]
    assert events[-1]["kind"] == "end" and events[-1]["score"] == 3150
    assert got["scores"][-1] == 3150 and got["scores"] == sorted(got["scores"])  # no penalty: never goes down
    result = got["result"]
    assert result["result"] == "succeeded" and result["score"] == 3150
    assert all(line in out for line in result["report"]), result["report"]
