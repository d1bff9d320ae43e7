"""sigcore.sim.contacts without a backend: the hold time in steps, the rolling parts, <drive casters> checks."""

from __future__ import annotations

from pathlib import Path

import pytest

from sigcore.sim.contacts import CONTACT_HOLD, hold_steps, rolling_parts
from sigcore.world import Robot, WorldError, parse_world
from sigcore.world.urdf import read_urdf

MINIBOT = Path(__file__).parent / "data" / "sim" / "minibot.urdf"


def _robot(tmp_path: Path, drive_extra: str) -> Robot:
    path = tmp_path / "world.xml"
    path.write_text(f'<world>\n  <robot name="bot" urdf="{MINIBOT}">\n'
                    f'    <drive left="wheel_l_joint" right="wheel_r_joint" radius="0.1" separation="0.36"'
                    f'{drive_extra}/>\n  </robot>\n</world>\n')
    robot = parse_world(path).agent("bot")
    assert isinstance(robot, Robot)
    return robot


def test_hold_is_whole_steps_rounded_up() -> None:
    """CONTACT_HOLD is 0.1 s: 50 steps of 2 ms; a hold that is not a whole number of steps rounds up; never 0."""
    assert CONTACT_HOLD == 0.1
    assert hold_steps(0.1, 0.002) == 50
    assert hold_steps(0.1, 0.003) == 34
    assert hold_steps(0.001, 0.01) == 1


@pytest.mark.parametrize(("hold", "dt"), [(0.0, 0.002), (0.1, 0.0), (-1.0, 0.002), (float("nan"), 0.002)])
def test_hold_refuses_non_positive_values(hold: float, dt: float) -> None:
    """A hold or timestep that is not a positive finite number is refused, naming both."""
    with pytest.raises(ValueError, match="hold and dt must be positive finite numbers"):
        hold_steps(hold, dt)


def test_rolling_parts_default_to_links_named_caster(tmp_path: Path) -> None:
    """Without casters=..., the rolling parts are the wheel joints' child links and every link named *caster*."""
    robot = _robot(tmp_path, "")
    assert robot.drive is not None and robot.drive.casters is None
    assert rolling_parts(robot, read_urdf(MINIBOT)) == {"wheel_l_link", "wheel_r_link", "caster_link",
                                                        "caster_front_link"}


@pytest.mark.parametrize(("casters", "expected"), [("caster_link", {"caster_link"}), ("", set()),
                                                    (" laser_link  caster_front_link ",
                                                     {"laser_link", "caster_front_link"})])
def test_casters_attribute_lists_the_casters(tmp_path: Path, casters: str, expected: set[str]) -> None:
    """casters="..." (space-separated, "" for none) replaces the name rule; the wheels always roll."""
    robot = _robot(tmp_path, f' casters="{casters}"')
    assert rolling_parts(robot, read_urdf(MINIBOT)) == {"wheel_l_link", "wheel_r_link"} | expected


def test_unknown_caster_link_is_located_with_the_valid_links(tmp_path: Path) -> None:
    """A casters link that the URDF does not have is one issue at the attribute's line:column, listing the links."""
    with pytest.raises(WorldError) as info:
        _robot(tmp_path, ' casters="caster_link ball_link"')
    [issue] = info.value.issues
    line = (tmp_path / "world.xml").read_text().splitlines()[2]
    assert (issue.line, issue.column) == (3, line.index("casters=") + 1)
    assert (issue.element, issue.attribute) == ("drive", "casters")
    assert f"no link 'ball_link' in {MINIBOT}" in issue.message
    assert "valid: space-separated links among base_link, wheel_l_link" in issue.message
