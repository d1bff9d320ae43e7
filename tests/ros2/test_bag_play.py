"""`sigcore bag play` (issue 15): a recording of tests/data/sim/world.xml (no ROS 2 while recording) is played into a
separate rclpy process (clients/bag_listen.py), which receives every ground-truth message in order, each after a
/clock that has reached its stamp, and the latched /tf_static although it subscribed before the player started;
bad bags are refused by name."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

pytest.importorskip("rclpy", reason="rclpy (ROS 2 Jazzy wheels) is not importable")
pytest.importorskip("sigcore_ros2", reason="the sigcore-ros2 plugin is not installed")

from rosbags.highlevel import AnyReader  # noqa: E402
from rosbags.typesys import Stores, get_typestore  # noqa: E402
from rosproc import CLIENTS, WORLD, _kill, ros_env  # noqa: E402

pytestmark = pytest.mark.ros2

SIGCORE = [sys.executable, "-m", "sigcore"]


@pytest.fixture(scope="module")
def played(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    tmp = tmp_path_factory.mktemp("bag_play")
    bag = tmp / "bag"
    subprocess.run([*SIGCORE, "run", str(WORLD), "--transport", "none", "--duration", "2", "-q", "--record",
                    str(bag)], check=True, capture_output=True, timeout=120)
    with AnyReader([bag], default_typestore=get_typestore(Stores.ROS2_JAZZY)) as reader:
        truth = [t for c, t, _ in reader.messages() if c.topic == "/sigcore/ground_truth"]
        static = [sorted(tf.child_frame_id for tf in reader.deserialize(raw, c.msgtype).transforms)
                  for c, _, raw in reader.messages() if c.topic == "/tf_static"]
    env = ros_env()
    listener = subprocess.Popen([sys.executable, str(CLIENTS / "bag_listen.py"), str(len(truth))], env=env,
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True)
    try:
        assert listener.stdout is not None and listener.stdout.readline().strip() == "listening"
        play = subprocess.run([*SIGCORE, "bag", "play", str(bag), "--rate", "4", "--delay", "0.5",
                               "--wait-for", "/sigcore/ground_truth", "--wait-for", "/clock", "--wait-for",
                               "/tf_static"], env=env,
                              capture_output=True, text=True, timeout=120)
        got, err = listener.communicate(timeout=90)
    finally:
        _kill(listener)  # type: ignore[arg-type]
    lines = [line for line in got.splitlines() if line.startswith("{")]
    assert lines, err[-3000:]
    return {"truth": truth, "static": static, "play": play, "seen": json.loads(lines[-1]), "bag": bag}


def test_the_player_played_every_message(played: dict) -> None:
    """bag play exits 0 and says how many messages it played: all of the bag's but its /clock (none here)."""
    play = played["play"]
    assert play.returncode == 0, play.stderr
    from sigcore.record.bag_reading import bag_info

    assert f"played {bag_info(played['bag']).messages} messages" in play.stdout


def test_every_ground_truth_message_arrives_in_order_after_its_clock(played: dict) -> None:
    """The listener receives every ground-truth message of the bag, in order; /clock carries each one's stamp and
    never goes back. (The player publishes that /clock before the message; the listener's executor may take two
    topics' messages in either order, so the order across topics is not asserted.)"""
    arrivals = played["seen"]["arrivals"]
    truth = [t for kind, t in arrivals if kind == "truth"]
    assert truth == played["truth"]
    clocks = [t for kind, t in arrivals if kind == "clock"]
    assert clocks == sorted(clocks) and len(set(clocks)) == len(clocks)
    assert set(truth) <= set(clocks)


def test_tf_static_is_latched_again(played: dict) -> None:
    """/tf_static, recorded latched, is played latched: the listener has it with the recorded frames."""
    assert played["static"] and played["seen"]["static"] == played["static"]


def test_a_cut_or_foreign_bag_is_refused_or_played_as_far_as_it_goes(played: dict, tmp_path: Path) -> None:
    """A foreign file: exit 2 naming it. A bag cut in the middle: a warning naming the file, the readable part is
    played (no traceback)."""
    foreign = tmp_path / "foreign"
    foreign.mkdir()
    (foreign / "foreign_0.mcap").write_bytes(b"PK\x03\x04 not a recording")
    out = subprocess.run([*SIGCORE, "bag", "play", str(foreign), "--delay", "0"], capture_output=True, text=True,
                         timeout=60, env=ros_env())
    assert out.returncode == 2 and "is not an MCAP file" in out.stderr and "Traceback" not in out.stderr
    cut = tmp_path / "cut"  # 30 s: several MCAP chunks, so the cut leaves whole chunks before it
    subprocess.run([*SIGCORE, "run", str(WORLD), "--transport", "none", "--duration", "30", "-q", "--record",
                    str(cut)], check=True, capture_output=True, timeout=120)
    (cut / "metadata.yaml").unlink()
    mcap = next(cut.glob("*.mcap"))
    with open(mcap, "r+b") as f:
        f.truncate(mcap.stat().st_size * 2 // 3)
    out = subprocess.run([*SIGCORE, "bag", "play", str(cut), "--rate", "100", "--delay", "0"], capture_output=True,
                         text=True, timeout=60, env=ros_env())
    assert out.returncode == 0 and "Traceback" not in out.stderr, out.stderr
    assert f"{mcap} is cut or damaged" in out.stderr
    assert int(out.stdout.split("played ")[1].split()[0]) > 100
