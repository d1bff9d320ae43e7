"""The clean-up task end to end over real ROS 2: simulator, robot node and moderator node as separate processes."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

pytest.importorskip("rclpy")
pytest.importorskip("sigcore_msgs")

ROOT = Path(__file__).parent.parent.parent


def test_cleanup_task_over_ros2_scores_every_item() -> None:
    """examples/cleanup/run_task.py exits 0; the referee scores 3 grasps and 3 correct boxes (3150), no penalty."""
    r = subprocess.run([sys.executable, str(ROOT / "examples" / "cleanup" / "run_task.py"), "--timeout", "200"],
                       capture_output=True, text=True, timeout=260, cwd=ROOT)
    out = r.stdout
    assert r.returncode == 0, out[-3000:] + r.stderr[-3000:]
    assert "succeeded" in out and "score 3150" in out
    assert sorted(re.findall(r"correct_box\s+\+1000\s+\d+\s+(\w+) in (\w+)", out)) == [
        ("apple_2", "trashbox_1"), ("can_0", "trashbox_2"), ("petbottle_1", "trashbox_0")]
    assert len(re.findall(r"\bgrasp\s+\+50", out)) == 3
    assert not re.search(r"\b(collision|wrong_box)\s+-", out)
    assert "robot_000 grasped can_0" in out
