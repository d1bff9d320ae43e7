"""No topic without a documented purpose: every topic of a live clean-up run is named in docs/ros2.md."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

pytest.importorskip("rclpy", reason="rclpy (ROS 2 Jazzy wheels) is not importable")

from rosproc import start_sim  # noqa: E402

from sigcore.world import Robot, parse_world  # noqa: E402

pytestmark = pytest.mark.ros2

ROOT = Path(__file__).resolve().parents[2]
CLEANUP = ROOT / "worlds" / "cleanup.xml"


def _suffixes() -> list[str]:
    """The topic suffixes of docs/api.md (its 'Topics each agent ...' tables)."""
    text = (ROOT / "docs" / "api.md").read_text()
    out = []
    for section in re.split(r"\n## ", text):
        if section.startswith("Topics each agent"):
            out += re.findall(r"^\| `(_[A-Za-z_]+)` \|", section, re.M)
    return out


def documented_patterns() -> list[tuple[str, re.Pattern[str]]]:
    """Each name in backquotes in docs/ros2.md that looks like a topic (absolute, or with a placeholder), as a
    regular expression; placeholders stand for the clean-up world's names (``<robot>``, ``<agent>``, ``<lidar>``,
    ``<entity>``) or docs/api.md's topic suffixes (``<suffix>``); another placeholder stands for any name."""
    world = parse_world(CLEANUP)
    robots = [a for a in world.agents if isinstance(a, Robot)]
    values = {"robot": [r.name for r in robots], "agent": [a.name for a in world.agents],
              "entity": [a.name for a in world.entities], "lidar": [li.name for r in robots for li in r.lidars],
              "suffix": _suffixes()}
    out = []
    for span in set(re.findall(r"`([^`\s]+)`", (ROOT / "docs" / "ros2.md").read_text())):
        if not (span.startswith("/") or span.startswith("<")) or ":" in span or "." in span \
                or re.fullmatch(r"<[a-z_]+>", span):  # not a name, or a lone placeholder
            continue
        parts = re.split(r"(<[a-z_]+>)", "/" + span.lstrip("/"))
        regex = ""
        for part in parts:
            if part.startswith("<"):
                names = values.get(part[1:-1])  # another placeholder: any name
                regex += "(?:" + "|".join(map(re.escape, names)) + ")" if names else "[A-Za-z0-9_]+"
            else:
                regex += re.escape(part)
        out.append((span, re.compile(regex)))
    return out


def test_every_live_topic_is_documented(tmp_path: Path) -> None:
    """Each topic a client process sees in the graph of worlds/cleanup.xml matches a name or pattern of
    docs/ros2.md (rclpy's own /rosout and /parameter_events included)."""
    patterns = documented_patterns()
    sim = start_sim(tmp_path, CLEANUP, "--realtime")
    try:
        topics = sim.client("graph_topics.py", timeout=90)["topics"]
    finally:
        sim.stop()
    assert len(topics) > 100
    undocumented = [t for t in topics if not any(p.fullmatch(t) for _, p in patterns)]
    assert not undocumented, f"{len(undocumented)} topics not in docs/ros2.md: {undocumented[:20]}"
