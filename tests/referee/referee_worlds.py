"""Small inline worlds for the referee tests: trash boxes from worlds/models, items, sigbot next to a wall."""

from __future__ import annotations

from pathlib import Path

from sigcore.sim import Simulation
from sigcore.world import parse_world

ROOT = Path(__file__).parent.parent.parent
TRASHBOX = ROOT / "worlds" / "models" / "trashbox" / "trashbox.urdf"
SIGBOT = ROOT / "worlds" / "models" / "sigbot" / "sigbot.urdf"

BOXES = f"""
  <object name="box_can" urdf="{TRASHBOX}" static="true" pose="0 0 0" tags="trashbox can"/>
  <object name="box_pet" urdf="{TRASHBOX}" static="true" pose="1 0 0" tags="trashbox recyclable petbottle"/>"""
ITEMS = """
  <object name="can_0" shape="cylinder" size="0.033 0.12" mass="0.05" pose="-1 1 0.06" graspable="true"
          tags="trash can"/>
  <object name="petbottle_1" shape="cylinder" size="0.033 0.2" mass="0.05" pose="-1.5 1 0.1" graspable="true"
          tags="trash petbottle"/>"""
ROBOT = f"""
  <robot name="robot_000" urdf="{SIGBOT}" pose="0 0 0 0 0 0">
    <drive type="differential" left="wheel_l_joint" right="wheel_r_joint" radius="0.1" separation="0.4"/>
    <gripper part="l_hand_link" grasp_radius="0.1" side="left"/>
    <gripper part="r_hand_link" grasp_radius="0.1" side="right"/>
  </robot>
  <object name="wall_west" shape="box" size="0.1 4 1" static="true" pose="-0.6 0 0.5" tags="wall"/>"""
MODERATOR = '\n  <agent name="moderator_0"/>'


def make_sim(tmp_path: Path, body: str, attributes: str = 'rules="cleanup"', backend: str = "mujoco") -> Simulation:
    """A simulation (MuJoCo unless told) of a world with ``<plugin name="referee" ATTRIBUTES/>`` and ``body``."""
    path = tmp_path / "world.xml"
    path.write_text(f'<world name="t" timestep="0.002">\n  <plugin name="referee" {attributes}/>{body}\n</world>\n')
    return Simulation(parse_world(path), backend)


def run_for(sim: Simulation, seconds: float) -> None:
    """Step ``sim`` for ``seconds`` simulated seconds."""
    sim.step(round(seconds / sim.dt))
