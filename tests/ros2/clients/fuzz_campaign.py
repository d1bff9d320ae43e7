"""A seeded campaign of randomised, hostile requests on every service and subscribed topic of the simulation's nodes.

Usage: fuzz_campaign.py SEED REQUESTS EXPECTED_JSON. EXPECTED_JSON lists the services and topics the world must have
(``{"services": [...], "topics": [...]}``); the campaign waits until the graph shows them, then calls every service
of the nodes /sigcore and /sigcore_actions and publishes on every topic /sigcore subscribes to, each at least once,
then random ones until REQUESTS requests were made. Field values are random and hostile: NaN, infinities, huge and
tiny numbers, extreme integers, 100 kB strings, unicode, control characters, empty and unknown names, long
sequences. Requests that would legitimately end or stall the run are left out (QUITTING, more than 100 steps), and
load_world only gets requests that cannot load a world. Afterwards it checks that the simulation still answers
correctly, then calls unload_world once (it takes every agent's endpoints away). Prints one JSON object.
"""

import importlib
import json
import math
import random
import sys
import time

import rclpy
from common import Client, emit, todict
from rcl_interfaces.srv import GetParameters, ListParameters
from rclpy.action import ActionClient
from rclpy.qos import QoSProfile, ReliabilityPolicy
from simulation_interfaces.action import SimulateSteps
from simulation_interfaces.msg import SimulationState
from simulation_interfaces.srv import GetEntityState, ResetSimulation, SetSimulationState, StepSimulation

CALL_TIMEOUT = 10.0
"""Every service must answer within this [s]."""

NODES = ("sigcore", "sigcore_actions")
NAMES = ["bot", "cube", "ball", "heavy", "wall", "man", "moderator", "main", "hand_link", "base_link",
         "elbow_joint", "shoulder_joint", "wheel_l_joint", "referee", "x", "world"]

seed, total, expected_file = int(sys.argv[1]), int(sys.argv[2]), sys.argv[3]
rng = random.Random(seed)
expected = json.loads(open(expected_file).read())


def hostile_string() -> str:
    return rng.choice([
        "", " ", "x" * 100_000, "é" * 5000, "名前🤖", "bot\n[ERROR] forged line", "\t\r\x1b[31m", "'\"; --",
        "../../etc/passwd", "%s%s%n", "{0}{1}", "[/tmp/data]", "nan", "-1", "a" * 256, "/bot", "bot ",
        *NAMES, rng.choice(NAMES) + rng.choice(["", "_", "2"])])


def hostile_float(bits: int) -> float:
    big = 3.0e38 if bits == 32 else 1.0e308
    tiny = 1e-45 if bits == 32 else 5e-324
    return rng.choice([math.nan, math.inf, -math.inf, big, -big, tiny, 0.0, -0.0, 1.0, -1.0,
                       rng.uniform(-10, 10), rng.uniform(-1e6, 1e6)])


INT_RANGES = {"int8": (-2**7, 2**7 - 1), "uint8": (0, 2**8 - 1), "int16": (-2**15, 2**15 - 1),
              "uint16": (0, 2**16 - 1), "int32": (-2**31, 2**31 - 1), "uint32": (0, 2**32 - 1),
              "int64": (-2**63, 2**63 - 1), "uint64": (0, 2**64 - 1), "byte": (0, 255), "char": (0, 255),
              "octet": (0, 255)}


def value_for(type_str: str, slot: object, depth: int = 0) -> object:
    """A random value for one field of ROS type ``type_str`` (as in ``get_fields_and_field_types``), ``slot`` its
    rosidl definition (in ``SLOT_TYPES``)."""
    if type_str.startswith("sequence<"):
        inner = type_str[len("sequence<"):-1].split(", ")[0]
        n = rng.choice([0, 1, 2, 3, 200]) if depth < 2 else rng.choice([0, 1])
        if "/" in inner:
            n = min(n, 3)
        return [value_for(inner, slot.value_type, depth + 1) for _ in range(n)]
    if type_str.endswith("]") and "[" in type_str:
        inner, size = type_str[:-1].split("[")
        return [value_for(inner, slot.value_type, depth + 1) for _ in range(int(size))]
    if type_str.startswith(("string", "wstring")):
        return hostile_string()
    if type_str in ("double", "float64"):
        return hostile_float(64)
    if type_str in ("float", "float32"):
        return hostile_float(32)
    if type_str == "boolean":
        return rng.random() < 0.5
    if type_str in INT_RANGES:
        lo, hi = INT_RANGES[type_str]
        v = rng.choice([lo, hi, 0, 1, rng.randint(lo, hi), rng.randint(max(lo, -5), min(hi, 300))])
        return bytes([v]) if type_str in ("byte", "octet") else v
    if "/" in type_str:  # a nested message: its class from the rosidl definition
        module = importlib.import_module(".".join(slot.namespaces))
        base, _, part = slot.name.rpartition("_")
        if not hasattr(module, slot.name) and part in ("Goal", "Result", "Feedback"):
            return build(getattr(getattr(module, base), part), depth + 1)  # inside an action
        return build(getattr(module, slot.name), depth + 1)
    raise ValueError(f"unknown field type {type_str}")


def build(cls: type, depth: int = 0) -> object:
    """A message of ``cls`` with random field values (a field whose value rclpy rejects keeps its default)."""
    msg = cls()
    for (field, type_str), slot in zip(msg.get_fields_and_field_types().items(), msg.SLOT_TYPES, strict=True):
        if depth > 4:
            break
        try:
            setattr(msg, field, value_for(type_str, slot, depth))
        except (AssertionError, TypeError, ValueError, OverflowError):
            pass
    return msg


def load(full: str, kind: str) -> type:
    """The Python class of ``pkg/kind/Name`` (``kind`` for ``pkg/Name`` inside a message definition)."""
    parts = full.split("/")
    pkg, name = parts[0], parts[-1]
    module = importlib.import_module(f"{pkg}.{parts[1] if len(parts) == 3 else kind}")
    for suffix, impl in (("_SendGoal", "SendGoalService"), ("_GetResult", "GetResultService")):
        if name.endswith(suffix):  # the services of an action
            return getattr(getattr(module, name.removesuffix(suffix)).Impl, impl)
    return getattr(module, name)


def tame(name: str, request: object) -> object:
    """Leave out what would legitimately end or stall the run (QUITTING, long step requests) or take endpoints
    away from the campaign (deleting an entity: its services would never answer again)."""
    if name.endswith("/set_simulation_state") and request.state.state == SimulationState.STATE_QUITTING:
        request.state.state = SimulationState.STATE_PAUSED
    if name.endswith("/delete_entity"):
        request.entity = "no_such_" + request.entity
    if name.endswith("/load_world"):  # never a world: a path that does not exist, text that is not XML
        request.uri = "/no_such_fuzz/" + request.uri if request.uri else ""
        request.resource_string = "x" + request.resource_string
    if name.endswith(("/step_simulation", "/_action/send_goal")):
        target = request.goal if hasattr(request, "goal") else request
        if 100 < target.steps <= 10_000_000:
            target.steps = rng.choice([1, 50, 100])
    return request


c = Client("fuzz_campaign")
c.wait_ready()
want_services, want_topics = set(expected["services"]), set(expected["topics"])
services: dict[str, str] = {}
topics: dict[str, str] = {}
end = time.monotonic() + 40
while time.monotonic() < end:  # discovery of hundreds of endpoints takes a moment
    c.spin(0.5)
    services = {n: t[0] for node in NODES
                for n, t in c.node.get_service_names_and_types_by_node(node, "/")}
    topics = {n: t[0] for n, t in c.node.get_subscriber_names_and_types_by_node("sigcore", "/")
              if n != "/clock"}
    if want_services <= set(services) and want_topics <= set(topics):
        break
clients = {n: c.node.create_client(load(t, "srv"), n) for n, t in services.items()}
qos = QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE)
pubs = {n: c.node.create_publisher(load(t, "msg"), n, qos) for n, t in topics.items()}
c.wait_for(lambda: all(p.get_subscription_count() > 0 for p in pubs.values()), 20.0)
# a request sent before the client is matched with its server is lost (in a ci-fresh run with four workers, the
# campaign's first call, made right after its client was created, was never answered): every client waits for its
# server (bounded: a client still unmatched then is what the campaign reports)
c.wait_for(lambda: all(cl.service_is_ready() for cl in clients.values()), 30.0)
c.spin(0.5)

endpoints = sorted(services) + sorted(topics)
order = rng.sample(endpoints, len(endpoints))
order += [rng.choice(endpoints) for _ in range(max(0, total - len(order)))]
unanswered: list[str] = []
detail: list = []
recent: list = []
calls: dict[str, int] = {}
published: dict[str, int] = {}
slowest = 0.0
t_start = time.monotonic()
for name in order:
    if name.endswith("/unload_world"):
        continue  # called once at the end
    if name in services:
        cls = load(services[name], "srv")
        request = tame(name, build(cls.Request))
        t0 = time.monotonic()
        future = clients[name].call_async(request)
        c.executor.spin_until_future_complete(future, timeout_sec=CALL_TIMEOUT)
        slowest = max(slowest, time.monotonic() - t0)
        calls[name] = calls.get(name, 0) + 1
        if not future.done():
            unanswered.append(name)
            detail.append([name, round(time.monotonic() - t_start, 2), str(request)[:300], recent[-8:]])
            clients[name].remove_pending_request(future)
        recent.append([name, round(time.monotonic() - t0, 3), str(request)[:120]])
    else:
        pubs[name].publish(build(load(topics[name], "msg")))
        published[name] = published.get(name, 0) + 1
        if published[name] % 20 == 0:
            c.spin(0.01)
# wrong types on command topics (no match: DDS keeps them apart; nothing may break)
# (on a node of its own context: one DDS participant cannot have one topic name with two types)
context = rclpy.context.Context()
rclpy.init(context=context)
stranger = rclpy.create_node("fuzz_wrong_types", context=context)
wrong = {}
for name in sorted(topics)[:5]:
    other = load("std_msgs/msg/String" if topics[name] != "std_msgs/msg/String" else "std_msgs/msg/Int32", "msg")
    wrong[name] = (stranger.create_publisher(other, name, 10), other)
c.spin(0.5)
for pub, other in wrong.values():
    pub.publish(build(other))
campaign_s = time.monotonic() - t_start
c.spin(1.0)

# afterwards: the parameter services answer, the simulation answers correctly
after: dict = {}
res = c.call(GetParameters, "/sigcore/get_parameters", names=["use_sim_time"])
after["use_sim_time"] = None if res is None else [[v.type, v.bool_value] for v in res.values]
res = c.call(ListParameters, "/sigcore/list_parameters")
after["parameters"] = None if res is None else sorted(res.result.names)
res = c.call(SetSimulationState, "/set_simulation_state", **{"state.state": SimulationState.STATE_PAUSED})
after["pause"] = None if res is None else res.result.result
res = c.call(ResetSimulation, "/reset_simulation")
after["reset"] = None if res is None else res.result.result
res = c.call(GetEntityState, "/get_entity_state", entity="wall")
after["wall"] = None if res is None else todict(res.state.pose.position)
srv_mod = importlib.import_module("sigcore_msgs.srv")
res = c.call(srv_mod.GetObjPosition, "/bot_get_obj_position", name="cube")
after["cube"] = None if res is None else todict(res)
t0 = c.call(srv_mod.GetTime, "/bot_get_time")
res = c.call(StepSimulation, "/step_simulation", steps=100)
after["step"] = None if res is None else res.result.result
t1 = c.call(srv_mod.GetTime, "/bot_get_time")
after["times"] = None if t0 is None or t1 is None else [t0.time, t1.time]
action = ActionClient(c.node, SimulateSteps, "/simulate_steps")
action.wait_for_server(timeout_sec=10)
goal_future = action.send_goal_async(SimulateSteps.Goal(steps=20))
c.executor.spin_until_future_complete(goal_future, timeout_sec=10)
goal = goal_future.result()
if goal is not None and goal.accepted:
    result_future = goal.get_result_async()
    c.executor.spin_until_future_complete(result_future, timeout_sec=30)
    after["action"] = result_future.result().result.result.result if result_future.done() else None
t2 = c.call(srv_mod.GetTime, "/bot_get_time")
after["time_after_action"] = None if t2 is None else t2.time
res = c.call(load("simulation_interfaces/srv/UnloadWorld", "srv"), "/unload_world")
calls["/unload_world"] = calls.get("/unload_world", 0) + 1
after["unload"] = None if res is None else res.result.result
emit({"requests": sum(calls.values()) + sum(published.values()) + len(wrong), "calls": calls,
      "published": published, "unanswered": unanswered, "detail": detail, "slowest": slowest, "campaign_s": campaign_s,
      "services": sorted(services), "topics": sorted(topics), "after": after})
