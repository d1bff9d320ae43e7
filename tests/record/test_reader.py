"""One reader of recordings (issue 29, item 5): ``sigcore.record.reader`` is what ``sigcore replay`` and the viewer's
playback read through; the replay's plan is in ``sigcore.record``; a backend states its own replay tolerance."""

from __future__ import annotations

import ast
from pathlib import Path

import numpy as np
import pytest
from sigcore_backend_bullet.backend import BulletBackend
from sigcore_backend_mujoco.backend import MujocoBackend

from sigcore.backend import Backend
from sigcore.publish import Offered
from sigcore.record.bag import BagWriter
from sigcore.record.reader import TruthReader, open_recording
from sigcore.record.recorder import _TfLayout
from sigcore.record.replay import Recording, plan_replay
from sigcore.record.serialize import Serializer
from sigcore.sim.exceptions import ReplayError
from sigcore.sim.inputs import Input

ROOT = Path(__file__).resolve().parents[2]


def imported_modules(path: Path) -> set[str]:
    """Every module ``path`` imports (inside functions too), relative imports resolved against its package."""
    tree = ast.parse(path.read_text())
    package = ".".join(path.relative_to(ROOT).with_suffix("").parts[:-1])
    for prefix in ("plugins.viewer.", "plugins.ros2."):
        package = package.removeprefix(prefix)
    out = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            out |= {a.name for a in node.names}
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")[: len(package.split(".")) - node.level + 1]
                out.add(".".join([*base, node.module] if node.module else base))
            elif node.module:
                out.add(node.module)
    return out


@pytest.mark.parametrize("client", ["plugins/viewer/sigcore_viewer/playback/recorded.py", "sigcore/cli/replay.py",
                                    "sigcore/cli/view.py", "sigcore/record/replay.py"])
def test_replay_and_playback_read_through_the_one_reader(client: str) -> None:
    """Neither the viewer's playback, the CLI nor the replay reads the container or the recorder's layout itself."""
    modules = imported_modules(ROOT / client)
    assert not modules & {"sigcore.record.bag_reading", "sigcore.record.bag", "mcap", "mcap.reader"}, modules
    text = (ROOT / client).read_text()
    assert "_TfLayout" not in text and "struct.unpack" not in text
    if not client.startswith("sigcore/cli/"):
        assert "sigcore.record.reader" in modules


def test_the_truth_reader_reads_the_recorders_layout_bit_for_bit() -> None:
    """Messages in the recorder's layout are read exactly (the second at the offsets the first gave); a message in
    another layout (another parent frame, other children) is read in full, and the next one of it too."""
    rng = np.random.default_rng(7)
    names = ["ground_truth/a", "ground_truth/robot/base_link"]
    layout = _TfLayout("world", names)
    reader = TruthReader(Serializer())
    for stamp in (0, 2_000_000, 4_000_000):
        poses = rng.normal(size=(2, 7))
        read = reader.poses(layout.pack(stamp, poses))
        assert list(read) == names
        assert all(np.array_equal(read[n], poses[i]) for i, n in enumerate(names))
    other = _TfLayout("map", ["x"])
    pose = rng.normal(size=(1, 7))
    assert np.array_equal(reader.poses(other.pack(6_000_000, pose))["x"], pose[0])
    assert np.array_equal(reader.poses(layout.pack(8_000_000, poses))[names[1]], poses[1])


def test_a_bag_sigcore_did_not_record_is_refused_naming_why(tmp_path: Path) -> None:
    with pytest.raises(ReplayError, match="no such file or directory"):
        open_recording(tmp_path / "missing")
    bag = tmp_path / "foreign"
    writer = BagWriter(bag)
    serializer = Serializer()
    topic = writer.add_topic("/chatter", "std_msgs/msg/String", *serializer.definition("std_msgs/msg/String"),
                             Offered(10))
    assert topic is not None
    writer.write(topic, 0, serializer.serialize("std_msgs/msg/String", {"data": "hi"}))
    writer.close()
    with pytest.raises(ReplayError, match="holds no 'sigcore' metadata record: it was not recorded by sigcore run"):
        open_recording(bag)


def _recording(inputs: list[Input], final: int) -> Recording:
    return Recording(Path("run"), None, {"timestep": "0.002"}, {}, inputs,  # type: ignore[arg-type]
                     [(0, {}), (final, {})])


def test_the_replay_plan_refuses_what_it_cannot_reproduce_before_it_runs() -> None:
    """Past the end, past a world load, or a command that cannot be applied again: refused with what is valid."""
    plain = _recording([Input(10, "reset", {"despawn": True})], 500)
    assert (plain_plan := plan_replay(plain)).target == 500 and plain_plan.whole
    assert plan_replay(plain, 200).target == 200 and not plan_replay(plain, 200).whole
    with pytest.raises(ReplayError, match=r"--until 600: the recording ends at step 500 \(t = 1.000 s\)"):
        plan_replay(plain, 600)
    loaded = _recording([Input(300, "world", {"what": "load_world"})], 500)
    with pytest.raises(ReplayError, match="first world ended at step 300.*--until 300 replays up to it"):
        plan_replay(loaded, 400)
    with pytest.raises(ReplayError, match="step 300: the run applied 'load_world'.*--until 300"):
        plan_replay(loaded)
    assert plan_replay(loaded, 300).target == 300


def test_each_backend_states_its_replay_tolerance() -> None:
    assert MujocoBackend.replay_tolerance == 0.0
    assert BulletBackend.replay_tolerance == 1e-6
    assert Backend.replay_tolerance == 1e-6  # a third-party backend that says nothing is not held to the bit
