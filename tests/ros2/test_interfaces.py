"""Tests of the ROS 2 typesupport generated from interfaces/ by scripts/build_interfaces.py.

They need a venv with the ROS 2 Jazzy wheels (scripts/ros2_requirements.txt) into which the interface packages
were built, and `rosbags` for the independent type-hash computation:

    <venv>/bin/python scripts/build_interfaces.py --venv <venv>
    <venv>/bin/python -m pytest tests/ros2/test_interfaces.py

The module is skipped where rclpy cannot be imported (e.g. the core's venv without the ROS 2 extras).
"""

from __future__ import annotations

import importlib
import json
import os
import signal
import subprocess
import sys
import textwrap
import time
import uuid
from pathlib import Path

import pytest
from rosdomains import next_domain

rclpy = pytest.importorskip("rclpy", reason="rclpy (ROS 2 Jazzy wheels) is not importable")

from rclpy.context import Context  # noqa: E402
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy  # noqa: E402

# rosidl's parser (lark-parser 0.12) imports modules deprecated since Python 3.11; not ours to fix.
pytestmark = [pytest.mark.ros2, pytest.mark.filterwarnings("ignore:module 'sre_:DeprecationWarning")]

REPO_ROOT = Path(__file__).resolve().parents[2]
INTERFACES_DIR = REPO_ROOT / "interfaces"
PACKAGES = ("tf2_msgs", "simulation_interfaces", "sigcore_msgs")
KINDS = ("msg", "srv", "action")

# Type hash of tf2_msgs/msg/TFMessage in ROS 2 Jazzy (what real ROS 2 nodes announce for /tf and /tf_static).
TFMESSAGE_TYPE = "tf2_msgs/msg/TFMessage"
TFMESSAGE_HASH_JAZZY = "RIHS01_e369d0f05a23ae52508854b66f6aa0437f3449d652e8cbf22d5abe85d020f087"

# RIHS01 type hashes (hex part) of the upstream Jazzy definitions of tf2_msgs and simulation_interfaces
# (1.5.1), recorded from a build of byte-identical copies of them. A change of interfaces/tf2_msgs or
# interfaces/simulation_interfaces that changes a hash breaks interoperability with real ROS 2 nodes.
UPSTREAM_TYPE_HASHES = {
    "tf2_msgs": {
        "action/LookupTransform": "0b8adf6bc0b5958879e3265b41a457e03558fe523890a81252c70eba97a82c5d",
        "msg/TF2Error": "db2485e7d6a0ec75bf087e058ee45df682acc3a621ca7780503d10aac141809a",
        "msg/TFMessage": "e369d0f05a23ae52508854b66f6aa0437f3449d652e8cbf22d5abe85d020f087",
        "srv/FrameGraph": "0d1fbc6222c018ba5f33822904a2fdd4063705289956d3fdde07cd8c50fe8067",
    },
    "simulation_interfaces": {
        "action/SimulateSteps": "f0837c898e1219cd73bf4c041feab41e8c533e8e1057e982744dba7b093467eb",
        "msg/Bounds": "e8624fe51f0f5548197542697d924c5699ac7198f1e4c68e50c3ca2af73f5b3f",
        "msg/EntityCategory": "43bdf7933fddf75f6970f7a8fe7078524355d821d390b3954bb46ac36c03dfe1",
        "msg/EntityFilters": "8e7b12e8ea062f14c55de4877221fe1b7cd9749665a7ad8a4ab855fc4b148303",
        "msg/EntityInfo": "3b9a2e7fa00f9a59d325b6e47904044c421561a385682027c7fc06c359806319",
        "msg/EntityState": "2e0464a85eb80a939025075d6c20761eca6a4cb9d6baf2c0ba373467c8b598d0",
        "msg/NamedPose": "b32da2a039b1840f605ec025b7991a18efacac662fac272818d1ae6e2b12bc27",
        "msg/Resource": "2bb1939cf80f8d2f284afba53cbec60b5ff33759bd39b714128ea8867a34c51a",
        "msg/Result": "cf43a306adff3337a0a47143d8f5689933bc70a30478f13b077dc1fe3bc5ad17",
        "msg/SimulationState": "bb9f87ccdd98fba113052a512d9801e84ce732d0a2b3c2b0cb281828de36e415",
        "msg/SimulatorFeatures": "8b101c8529bc0ea3dcf056078254768f39832b9ef0adaf93bd5cea96c0de3305",
        "msg/SpawnEntity": "94a349a865ccf673c18c080520299c88c3d8d5f4842ecf1482d6c997ac4b69f9",
        "msg/SpawnResult": "dbc277304b6c24bfb2a631cea8f52e2b005d583ec0a6c86b11613f5ce6486da1",
        "msg/Spawnable": "8c22025d840e7a05ab31ba56f998b06458b549a9744b4695be25b778829fc176",
        "msg/TagsFilter": "5c3efc51e8ed04c266c09cb4691ec95b964cd410558e01d8c83646b038826b45",
        "msg/WorldResource": "e3b65ecf904b9b115673e4a343c6aa3d28c19e185a71228faa64b783afcf2403",
        "srv/DeleteEntity": "ff7e96a5b83dc8e2bb34b8b034480028b3a24d9f8376b2c0590bac3704be3e28",
        "srv/GetAvailableWorlds": "ce5589b5523f2732d1969a3c5a7e6b17a387091df8190c62f78d7fdd1109e3e3",
        "srv/GetCurrentWorld": "79ed4e910e1b7a1c9f7950ff758bfba3535bf0dec669054e8af115a099724ddd",
        "srv/GetEntities": "cb90004c48cd50f37732fb008e22c34c261dd680a723bf0f85d8437ea4498bf7",
        "srv/GetEntitiesStates": "0a76170d0c1c90e1eaf805cfab78ea801d1f82df309a28c1f0fae4b570f19754",
        "srv/GetEntityBounds": "17be8d36231178a5eed0de0344b55c19975581627a9aec30a4fee9926a35deed",
        "srv/GetEntityInfo": "953b7ab6bfc35063f5c9a72463c6ce489baa10249a7fa510926d342a34b0d29e",
        "srv/GetEntityState": "749c91f2a2353d98367b64f2995a0f5842ce92a08ec1ffb3e185540a91557fb5",
        "srv/GetNamedPoseBounds": "59fa8dd2c68ba6771160cc66a628ac99fa95e2748fa0a43c2cc62a2e5f3f6fdc",
        "srv/GetNamedPoses": "c3d12ab920115bfd4733f6d20516adc3968fb438538540997c37e200e02b04e3",
        "srv/GetSimulationState": "3362dcebee4b1afebbf9c4beee5c79c1455385aded62092a892d61fde8644f30",
        "srv/GetSimulatorFeatures": "abb9439c8cf196722a469fb6c68b44b484f198c2a1356ac38849a29c2a20a794",
        "srv/GetSpawnables": "3bc0266bf8236058ff589c44512e013afe4f295427c39d44cff363d1c956bf36",
        "srv/LoadWorld": "f210682338f195f6f06191b46b20ec4992bddf485d33e2cffab2dd15341b4e3e",
        "srv/ResetSimulation": "4ce285d7ff9b8ac70dcc95161f32bf54c05a6f4b13427990e41ab40c36c39646",
        "srv/SetEntityInfo": "867fe2b6812f3e021859171f9b788560d66bb7079d640030baf6c0bb2dd2631e",
        "srv/SetEntityState": "ca210e7d2b66629ae133c8e1edf5246e618106d75c78ed0556c0e7a33c59ee5e",
        "srv/SetSimulationState": "a868b916dce49974f637ba252141258c4b07b0c06858b88af560e3eb6bfbcb30",
        "srv/SpawnEntities": "41703a359ee032bf4fc230f144f531705ba039a2e97edeae1f7997dd83b04857",
        "srv/SpawnEntity": "d4c086345d4194a5fc4c9ae45095736ca4062b5cdac4d06a42dec93d683e03cf",
        "srv/StepSimulation": "913fe0653690ce6bf8f09f316e6a626747012e9fca31e26719910d417aa8565c",
        "srv/UnloadWorld": "ac7f9a73df1b5b15015d854c5ac552b7726506e22f886c6792804f0b7f88b30b",
    },
}


def _source_types() -> list[tuple[str, str, str]]:
    """List (package, kind, name) of every interface definition in interfaces/ for the packages under test."""
    return [
        (pkg, kind, f.stem)
        for pkg in PACKAGES
        for kind in KINDS
        for f in sorted((INTERFACES_DIR / pkg / kind).glob(f"*.{kind}"))
    ]


SOURCE_TYPES = _source_types()
SOURCE_MESSAGES = [t for t in SOURCE_TYPES if t[1] == "msg"]


def _installed_description(pkg: str, kind: str, name: str) -> dict:
    """Load the type description JSON that rosidl generated and installed for one type.

    Fails (rather than skips) when it is missing: rclpy is there, so the interfaces should have been built.
    """
    path = Path(sys.prefix) / "share" / pkg / kind / f"{name}.json"
    if not path.is_file():
        pytest.fail(f"{path} not found: run scripts/build_interfaces.py --venv {sys.prefix}")
    return json.loads(path.read_text())


def _generated_hashes(pkg: str, kind: str, name: str) -> dict[str, str]:
    """Map each type name in a generated type description (the type and all it refers to) to its hash."""
    return {h["type_name"]: h["hash_string"] for h in _installed_description(pkg, kind, name)["type_hashes"]}


def _domain_id() -> int:
    """A ROS domain ID for this test run, so parallel or leftover runs do not talk to each other."""
    return next_domain()


@pytest.fixture
def ros_env(monkeypatch: pytest.MonkeyPatch) -> dict[str, str]:
    """Environment of this process and its children: own domain, discovery limited to this machine."""
    monkeypatch.setenv("ROS_DOMAIN_ID", str(_domain_id()))
    monkeypatch.setenv("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
    monkeypatch.delenv("ROS_STATIC_PEERS", raising=False)
    return dict(os.environ)


@pytest.fixture
def node(ros_env: dict[str, str]):
    """A node in its own rclpy context, shut down after the test."""
    context = Context()
    rclpy.init(context=context)
    node = rclpy.create_node(f"sigcore_test_{uuid.uuid4().hex[:8]}", context=context)
    try:
        yield node
    finally:
        node.destroy_node()
        rclpy.shutdown(context=context)


# ------------------------------------------------------------------------------------------------------------
# Imports and the Jazzy hash of TFMessage
# ------------------------------------------------------------------------------------------------------------


def test_generated_modules_import() -> None:
    """The generated Python modules of the three packages import in this venv."""
    from sigcore_msgs.msg import OnCollisionMsg
    from sigcore_msgs.srv import GetObjPosition
    from simulation_interfaces.action import SimulateSteps
    from simulation_interfaces.srv import GetEntities
    from tf2_msgs.msg import TFMessage

    assert TFMessage().transforms == []
    assert GetEntities.Request().filters.filter == ""
    assert SimulateSteps.Goal().steps == 0
    assert GetObjPosition.Response().success is False
    assert OnCollisionMsg(name="table", part="WAIST").part == "WAIST"


def test_tfmessage_hash_in_generated_description() -> None:
    """The generated type description of tf2_msgs/msg/TFMessage carries the ROS 2 Jazzy type hash."""
    assert _generated_hashes("tf2_msgs", "msg", "TFMessage")[TFMESSAGE_TYPE] == TFMESSAGE_HASH_JAZZY


def test_upstream_packages_keep_jazzy_hashes() -> None:
    """Every type of our tf2_msgs and simulation_interfaces has the hash of the upstream Jazzy type."""
    generated = {
        f"{pkg}/{kind}/{name}": _generated_hashes(pkg, kind, name)[f"{pkg}/{kind}/{name}"]
        for pkg, kind, name in SOURCE_TYPES
        if pkg in UPSTREAM_TYPE_HASHES
    }
    upstream = {
        f"{pkg}/{typename}": f"RIHS01_{hex_digest}"
        for pkg, hashes in UPSTREAM_TYPE_HASHES.items()
        for typename, hex_digest in hashes.items()
    }
    assert generated == upstream


def _publisher_type_hash(node, msg_type, topic: str) -> str:
    """Create a publisher and return the type hash its compiled typesupport announces in the ROS graph."""
    node.create_publisher(msg_type, topic, 1)
    deadline = time.monotonic() + 5.0
    while time.monotonic() < deadline:
        infos = node.get_publishers_info_by_topic(topic)
        if infos:
            return str(infos[0].topic_type_hash)
        time.sleep(0.05)
    pytest.fail(f"own publisher on {topic} never appeared in the graph")


def test_tfmessage_hash_of_compiled_typesupport(node) -> None:
    """A TFMessage publisher announces the ROS 2 Jazzy type hash (the one compiled into the typesupport)."""
    from tf2_msgs.msg import TFMessage

    assert _publisher_type_hash(node, TFMessage, "/sigcore_test_tf") == TFMESSAGE_HASH_JAZZY


def test_message_hashes_of_compiled_typesupport(node) -> None:
    """Every message type's compiled typesupport announces the same hash as its generated type description."""
    mismatches = {}
    for i, (pkg, kind, name) in enumerate(SOURCE_MESSAGES):
        msg_type = getattr(importlib.import_module(f"{pkg}.{kind}"), name)
        announced = _publisher_type_hash(node, msg_type, f"/sigcore_test_hash_{i}")
        expected = _generated_hashes(pkg, kind, name)[f"{pkg}/{kind}/{name}"]
        if announced != expected:
            mismatches[f"{pkg}/{kind}/{name}"] = (announced, expected)
    assert not mismatches


# ------------------------------------------------------------------------------------------------------------
# Independent hash computation with rosbags
# ------------------------------------------------------------------------------------------------------------


def _split_parts(text: str) -> list[str]:
    """Split a .srv/.action definition at its '---' separator lines."""
    parts: list[list[str]] = [[]]
    for line in text.splitlines():
        if line.strip() == "---":
            parts.append([])
        else:
            parts[-1].append(line)
    return ["\n".join(p) + "\n" for p in parts]


class _RosbagsHasher:
    """Computes RIHS01 type hashes with rosbags from the .msg/.srv/.action sources in interfaces/.

    rosbags parses and hashes messages; ROS 2 describes a service or an action as messages too, with a fixed
    layout (REP-2011, rosidl_generator_type_description), which this class builds: for service S, S_Request
    and S_Response from the definition, S_Event {info, request[<=1], response[<=1]} and S {request_message,
    response_message, event_message}; for action A, A_Goal, A_Result, A_Feedback from the definition, the
    services A_SendGoal {goal_id, goal} -> {accepted, stamp} and A_GetResult {goal_id} -> {status, result},
    the message A_FeedbackMessage {goal_id, feedback} and A {goal, result, feedback, send_goal_service,
    get_result_service, feedback_message}.

    The store starts as rosbags' Jazzy store, which already holds upstream's tf2_msgs: registering our copy of
    a type that differs from upstream raises, so the tf2_msgs hashes compare upstream's definitions with ours.

    One difference is reconciled: rosbags hashes a .msg `char` field as the IDL type char, while rosidl
    converts .msg `char` to uint8 (rosidl_adapter); this matters for service_msgs/ServiceEventInfo
    (`char[16] client_gid`), part of every service's type description.
    """

    def __init__(self) -> None:
        from rosbags.interfaces import Nodetype
        from rosbags.typesys import Stores, get_types_from_msg, get_typestore

        self._nodetype = Nodetype
        self._parse_msg = get_types_from_msg
        self.store = get_typestore(Stores.ROS2_JAZZY)
        for pkg, kind, name in SOURCE_TYPES:
            text = (INTERFACES_DIR / pkg / kind / f"{name}.{kind}").read_text()
            getattr(self, f"_add_{kind}")(pkg, name, text)
        for typename, (consts, fields) in list(self.store.fielddefs.items()):
            self.store.fielddefs[typename] = (consts, [(f, self._char_as_uint8(d)) for f, d in fields])

    def _char_as_uint8(self, desc: tuple) -> tuple:
        """Map the base type `char` to `uint8` in a rosbags field descriptor, as rosidl does for .msg."""
        if desc[0] == self._nodetype.BASE:
            return (desc[0], ("uint8", desc[1][1])) if desc[1][0] == "char" else desc
        if desc[0] in (self._nodetype.ARRAY, self._nodetype.SEQUENCE):
            return (desc[0], (self._char_as_uint8(desc[1][0]), desc[1][1]))
        return desc

    def _ref(self, typename: str) -> tuple:
        return (self._nodetype.NAME, typename)

    def _base(self, base_type: str) -> tuple:
        return (self._nodetype.BASE, (base_type, 0))

    def _at_most_one(self, typename: str) -> tuple:
        return (self._nodetype.SEQUENCE, (self._ref(typename), 1))

    def _fields(self, pkg: str, text: str) -> tuple[list, list]:
        """Parse a message body; type references resolve within `pkg` as in ROS (pkg/msg/...)."""
        tmp = f"{pkg}/msg/SigcoreHashProbe"
        return self._parse_msg(text, tmp)[tmp]

    def _register(self, typs: dict) -> None:
        self.store.register(typs)

    def _add_msg(self, pkg: str, name: str, text: str) -> None:
        self._register({f"{pkg}/msg/{name}": self._fields(pkg, text)})

    def _service(self, base: str, request: tuple[list, list], response: tuple[list, list]) -> dict:
        return {
            f"{base}_Request": request,
            f"{base}_Response": response,
            f"{base}_Event": (
                [],
                [
                    ("info", self._ref("service_msgs/msg/ServiceEventInfo")),
                    ("request", self._at_most_one(f"{base}_Request")),
                    ("response", self._at_most_one(f"{base}_Response")),
                ],
            ),
            base: (
                [],
                [
                    ("request_message", self._ref(f"{base}_Request")),
                    ("response_message", self._ref(f"{base}_Response")),
                    ("event_message", self._ref(f"{base}_Event")),
                ],
            ),
        }

    def _add_srv(self, pkg: str, name: str, text: str) -> None:
        request, response = _split_parts(text)
        self._register(
            self._service(f"{pkg}/srv/{name}", self._fields(pkg, request), self._fields(pkg, response))
        )

    def _add_action(self, pkg: str, name: str, text: str) -> None:
        goal, result, feedback = _split_parts(text)
        base = f"{pkg}/action/{name}"
        goal_id = ("goal_id", self._ref("unique_identifier_msgs/msg/UUID"))
        typs = {
            f"{base}_Goal": self._fields(pkg, goal),
            f"{base}_Result": self._fields(pkg, result),
            f"{base}_Feedback": self._fields(pkg, feedback),
            f"{base}_FeedbackMessage": ([], [goal_id, ("feedback", self._ref(f"{base}_Feedback"))]),
        }
        typs.update(
            self._service(
                f"{base}_SendGoal",
                ([], [goal_id, ("goal", self._ref(f"{base}_Goal"))]),
                ([], [("accepted", self._base("bool")), ("stamp", self._ref("builtin_interfaces/msg/Time"))]),
            )
        )
        typs.update(
            self._service(
                f"{base}_GetResult",
                ([], [goal_id]),
                ([], [("status", self._base("int8")), ("result", self._ref(f"{base}_Result"))]),
            )
        )
        typs[base] = (
            [],
            [
                ("goal", self._ref(f"{base}_Goal")),
                ("result", self._ref(f"{base}_Result")),
                ("feedback", self._ref(f"{base}_Feedback")),
                ("send_goal_service", self._ref(f"{base}_SendGoal")),
                ("get_result_service", self._ref(f"{base}_GetResult")),
                ("feedback_message", self._ref(f"{base}_FeedbackMessage")),
            ],
        )
        self._register(typs)

    def hash(self, typename: str) -> str:
        """Return the RIHS01 hash rosbags computes for a type name (e.g. 'pkg/srv/Name_Event')."""
        return self.store.hash_rihs01(typename)


@pytest.fixture(scope="module")
def rosbags_hasher() -> _RosbagsHasher:
    """rosbags' Jazzy type store extended with every definition of interfaces/."""
    pytest.importorskip("rosbags", reason="rosbags is needed for the independent type-hash computation")
    return _RosbagsHasher()


def test_rosbags_jazzy_store_gives_tfmessage_hash(rosbags_hasher: _RosbagsHasher) -> None:
    """rosbags, independently of rosidl, computes the ROS 2 Jazzy hash for our tf2_msgs/msg/TFMessage."""
    assert rosbags_hasher.hash(TFMESSAGE_TYPE) == TFMESSAGE_HASH_JAZZY


@pytest.mark.parametrize(("pkg", "kind", "name"), SOURCE_TYPES, ids=["/".join(t) for t in SOURCE_TYPES])
def test_generated_hashes_match_rosbags(
    rosbags_hasher: _RosbagsHasher, pkg: str, kind: str, name: str
) -> None:
    """The generated hashes of a type and of all types it refers to equal rosbags' hashes of the sources."""
    generated = _generated_hashes(pkg, kind, name)
    assert f"{pkg}/{kind}/{name}" in generated
    computed = {typename: rosbags_hasher.hash(typename) for typename in generated}
    assert computed == generated


# ------------------------------------------------------------------------------------------------------------
# Across processes
# ------------------------------------------------------------------------------------------------------------

# A subscriber in a child process: prints "ready", then the first TFMessage it receives as JSON, then exits.
_SUBSCRIBER = textwrap.dedent(
    """
    import json, sys
    import rclpy
    from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
    from tf2_msgs.msg import TFMessage

    topic, durability = sys.argv[1], sys.argv[2]
    rclpy.init()
    node = rclpy.create_node("sigcore_test_tf_listener")
    received = []
    qos = QoSProfile(
        depth=10, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy[durability]
    )
    node.create_subscription(TFMessage, topic, received.append, qos)
    print("ready", flush=True)
    while not received:
        rclpy.spin_once(node, timeout_sec=0.1)
    t = received[0].transforms[0]
    print(json.dumps({"child": t.child_frame_id, "parent": t.header.frame_id, "x": t.transform.translation.x,
                      "sec": t.header.stamp.sec}), flush=True)
    node.destroy_node()
    rclpy.shutdown()
    """
)


def _tf_message():
    """A TFMessage with one transform world -> robot_000/base_link."""
    from geometry_msgs.msg import TransformStamped
    from tf2_msgs.msg import TFMessage

    t = TransformStamped()
    t.header.frame_id = "world"
    t.header.stamp.sec = 42
    t.child_frame_id = "robot_000/base_link"
    t.transform.translation.x = 1.5
    t.transform.rotation.w = 1.0
    return TFMessage(transforms=[t])


@pytest.mark.parametrize("durability", ["VOLATILE", "TRANSIENT_LOCAL"])
def test_tfmessage_pubsub_across_processes(node, ros_env: dict[str, str], durability: str) -> None:
    """A TFMessage published here arrives intact in a subscriber in another process (volatile/latched)."""
    from tf2_msgs.msg import TFMessage

    topic = f"/sigcore_test_tf_{uuid.uuid4().hex[:8]}"
    qos = QoSProfile(
        depth=10, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy[durability]
    )
    publisher = node.create_publisher(TFMessage, topic, qos)
    message = _tf_message()
    latched = durability == "TRANSIENT_LOCAL"
    if latched:
        publisher.publish(message)  # published once, before the subscriber exists, like /tf_static

    child = subprocess.Popen(
        [sys.executable, "-c", _SUBSCRIBER, topic, durability],
        env=ros_env,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,  # own process group, killed below whatever happens
    )
    try:
        deadline = time.monotonic() + 30.0
        while child.poll() is None and time.monotonic() < deadline:
            if not latched:
                publisher.publish(message)
            time.sleep(0.1)
        assert child.poll() is not None, "the subscriber received nothing within 30 s"
        out, err = child.communicate(timeout=5)
        assert child.returncode == 0, err
        lines = out.splitlines()
        assert lines[0] == "ready"
        assert json.loads(lines[-1]) == {
            "child": "robot_000/base_link",
            "parent": "world",
            "x": 1.5,
            "sec": 42,
        }
    finally:
        try:
            os.killpg(child.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
        child.wait(timeout=5)
