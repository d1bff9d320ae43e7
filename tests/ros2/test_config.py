"""Settings of the ROS 2 transport from <plugin name="ros2" .../>: parsing, validation, and their effect."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

pytest.importorskip("rclpy", reason="rclpy (ROS 2 Jazzy wheels) is not importable")
pytest.importorskip("sigcore_ros2", reason="the sigcore-ros2 plugin is not installed")

from rosproc import WORLD, start_sim  # noqa: E402
from sigcore_ros2.config import Ros2Config, config_for, parse_qos  # noqa: E402

from sigcore.sim import Simulation  # noqa: E402
from sigcore.world import WorldError, parse_world  # noqa: E402
from sigcore.world.plugin_config import validate_plugin  # noqa: E402

pytestmark = pytest.mark.ros2


def test_qos_overrides_parse() -> None:
    """'TOPIC: words' entries become per-topic overrides; a missing slash is added."""
    qos = parse_qos("/clock: best_effort depth=1; bot/scan: transient_local keep_all")
    assert qos["/clock"].reliable is False and qos["/clock"].depth == 1
    assert qos["/bot/scan"].transient_local is True and qos["/bot/scan"].depth == 0


@pytest.mark.parametrize(("attribute", "match"), [
    ('qos="/clock: fast"', "unknown word 'fast' for /clock; valid: reliable"),
    ('qos="/clock best_effort"', "is not 'TOPIC: WORDS'"),
    ('clock_rte="10"', r"unknown attribute of plugin 'ros2' \(did you mean 'clock_rate'\?\); valid: name, clock_rate"),
    ('state_rate="0"', r"'0' is out of range; valid: state_rate > 0 \[Hz\]"),
    ('sim_prefix="sim space"', "not a ROS namespace"),
    ('standard="maybe"', "'maybe' is not a boolean; valid: true, false"),
])
def test_bad_settings_are_refused_with_what_is_valid(tmp_path: Path, attribute: str, match: str) -> None:
    """A bad attribute is reported at its line:column, naming itself and what would be valid."""
    world = tmp_path / "world.xml"
    world.write_text(f'<world name="w">\n  <plugin name="ros2" clock_rate="10" {attribute}/>\n</world>\n')
    with pytest.raises(WorldError) as info:
        validate_plugin(parse_world(world), parse_world(world).plugins[0], Ros2Config)
    [issue] = info.value.issues
    assert (issue.line, issue.column, issue.attribute) == (2, 39, attribute.split("=")[0])
    assert re.search(match, issue.message), issue.message


def test_config_for_reads_the_world_element(tmp_path: Path) -> None:
    """The transport's settings are the world's <plugin name="ros2"> element through the same model."""
    world = tmp_path / "world.xml"
    world.write_text('<world name="w">\n  <plugin name="ros2" clock_rate="25" sigros="false"/>\n</world>\n')
    config = config_for(Simulation(parse_world(world), "mujoco"))
    assert (config.clock_rate, config.sigros, config.standard) == (25.0, False, True)


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
    # /clock is best effort here: a message may be lost on a loaded machine, so every gap is a whole number of
    # 0.01 s periods, and the shortest is one period (published at 100 Hz of simulated time)
    gaps = [round(b - a, 9) for a, b in zip(clock, clock[1:], strict=False)]
    assert len(clock) > 5 and min(gaps) == 0.01, clock
    assert all(g >= 0.01 and abs(g / 0.01 - round(g / 0.01)) < 1e-6 for g in gaps), clock
    assert out["prefixed_state"] == 1  # /sim/get_simulation_state answers: playing
    assert out["sigros"] is False
