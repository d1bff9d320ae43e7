"""Settings of the ROS 2 transport from <plugin name="ros2" .../>: parsing, validation, and their effect."""

from __future__ import annotations

from pathlib import Path

import pytest

pytest.importorskip("rclpy", reason="rclpy (ROS 2 Jazzy wheels) is not importable")
pytest.importorskip("sigcore_ros2", reason="the sigcore-ros2 plugin is not installed")

from rosproc import WORLD, start_sim  # noqa: E402
from sigcore_ros2.config import Ros2Config, parse_qos  # noqa: E402


def test_qos_overrides_parse() -> None:
    """'TOPIC: words' entries become per-topic overrides; a missing slash is added."""
    qos = parse_qos("/clock: best_effort depth=1; bot/scan: transient_local keep_all")
    assert qos["/clock"].reliable is False and qos["/clock"].depth == 1
    assert qos["/bot/scan"].transient_local is True and qos["/bot/scan"].depth == 0


@pytest.mark.parametrize(("attrs", "match"), [
    ({"qos": "/clock: fast"}, "unknown word 'fast'.*valid: reliable"),
    ({"qos": "/clock best_effort"}, "is not 'TOPIC: WORDS'"),
    ({"clock_rte": "10"}, "unknown attribute.*clock_rte.*valid: clock_rate"),
    ({"state_rate": "0"}, "state_rate"),
    ({"sim_prefix": "sim space"}, "not a ROS namespace"),
])
def test_bad_settings_are_refused_with_what_is_valid(attrs: dict[str, str], match: str) -> None:
    """A bad attribute names itself and what would be valid."""
    with pytest.raises(ValueError, match=match):
        Ros2Config.from_attributes(attrs)


def test_world_settings_change_qos_rates_and_prefix(tmp_path: Path) -> None:
    """clock_rate, qos overrides and sim_prefix from the world file take effect over ROS 2."""
    text = WORLD.read_text().replace('urdf="minibot.urdf"', f'urdf="{WORLD.parent / "minibot.urdf"}"')
    plugin = ('<plugin name="ros2" clock_rate="100" sim_prefix="/sim" sigros="false" '
              'qos="/clock: best_effort; /bot/scan: best_effort depth=2"/>')
    world = tmp_path / "world.xml"
    world.write_text(text.replace('timestep="0.002">', f'timestep="0.002">\n  {plugin}', 1))
    sim = start_sim(tmp_path, world, "--realtime")
    try:
        out = sim.client("qos.py")
    finally:
        sim.stop()
    assert out["qos"]["/clock"][0] == "BEST_EFFORT" and out["qos"]["/bot/scan"][:2] == ["BEST_EFFORT", "VOLATILE"]
    clock = out["clock"]
    assert len(clock) > 5 and all(abs(b - a - 0.01) < 1e-9 for a, b in zip(clock, clock[1:], strict=False))
    assert out["prefixed_state"] == 1  # /sim/get_simulation_state answers: playing
    assert out["sigros"] is False
