"""The read side of simulation_interfaces on worlds/cleanup.xml (paused): entity information, bounds, filters,
named poses, simulate_steps feedback, and the refusals of bad input."""

import math

from common import Client, emit
from geometry_msgs.msg import Vector3
from rclpy.action import ActionClient
from rclpy.qos import QoSProfile
from simulation_interfaces.action import SimulateSteps
from simulation_interfaces.msg import Bounds, EntityCategory, TagsFilter
from simulation_interfaces.srv import (
    GetEntities,
    GetEntityBounds,
    GetEntityInfo,
    GetEntityState,
    GetNamedPoseBounds,
    GetNamedPoses,
    GetSimulatorFeatures,
    ResetSimulation,
    SetEntityInfo,
)

c = Client("siminfo_probe")
c.wait_ready()
out = {}


def info(name):
    r = c.call(GetEntityInfo, "/get_entity_info", entity=name)
    return {"result": r.result.result, "message": r.result.error_message, "category": r.info.category.category,
            "description": r.info.description, "tags": list(r.info.tags)}


def entities(**fields):
    r = c.call(GetEntities, "/get_entities", **fields)
    return {"result": r.result.result, "message": r.result.error_message, "entities": list(r.entities)}


def bounds(kind, *points):
    # floats, never ints: the C conversion of a float64 field reads an int object as garbage
    return Bounds(type=kind, points=[Vector3(x=float(p[0]), y=float(p[1]), z=float(p[2])) for p in points])


def box(b):
    return {"type": b.type, "points": [[p.x, p.y, p.z] for p in b.points]}


def set_info(name, category, description, tags):
    r = c.call(SetEntityInfo, "/set_entity_info", entity=name, **{"info.category.category": category,
                                                                    "info.description": description,
                                                                    "info.tags": tags})
    return {"result": r.result.result, "message": r.result.error_message}


out["features"] = sorted(c.call(GetSimulatorFeatures, "/get_simulator_features").features.features)
out["info"] = {n: info(n) for n in ("can_0", "table_0", "robot_000", "man_0", "trashbox_2")}

# set_entity_info, then get_entity_info and the filters see it
out["set"] = set_info("can_0", EntityCategory.CATEGORY_DYNAMIC_OBJECT, "a red can", ["trash", "can", "red"])
out["after_set"] = info("can_0")
out["tag_red"] = entities(**{"filters.tags.tags": ["red"]})
out["tag_all"] = entities(**{"filters.tags.tags": ["trash", "red"],
                             "filters.tags.filter_mode": TagsFilter.FILTER_MODE_ALL})
out["dynamic"] = entities(**{"filters.categories": [EntityCategory(category=EntityCategory.CATEGORY_DYNAMIC_OBJECT)]})
out["humans_robots"] = entities(**{"filters.categories": [EntityCategory(category=EntityCategory.CATEGORY_HUMAN),
                                                          EntityCategory(category=EntityCategory.CATEGORY_ROBOT)]})

# bounds
r = c.call(GetEntityBounds, "/get_entity_bounds", entity="table_0")
out["table_bounds"] = {"result": r.result.result, **box(r.bounds)}
can = c.call(GetEntityState, "/get_entity_state", entity="can_0").state.pose.position
out["can_at"] = [can.x, can.y, can.z]
out["sphere_can"] = entities(**{"filters.bounds": bounds(Bounds.TYPE_SPHERE, (can.x, can.y, can.z), (0.05, 0, 0))})
out["box_bin"] = entities(**{"filters.bounds": bounds(Bounds.TYPE_BOX, (-1.9, -2.1, 0.5), (-2.1, -2.3, 0.1))})

# named poses
r = c.call(GetNamedPoses, "/get_named_poses")
out["poses"] = {p.name: {"tags": list(p.tags), "description": p.description,
                         "pose": [p.pose.position.x, p.pose.position.y, p.pose.position.z,
                                  p.pose.orientation.w, p.pose.orientation.x, p.pose.orientation.y,
                                  p.pose.orientation.z]} for p in r.poses}
out["poses_result"] = r.result.result
out["poses_spawn"] = [p.name for p in c.call(GetNamedPoses, "/get_named_poses", **{"tags.tags": ["spawn"]}).poses]
out["poses_drop_0"] = [p.name for p in c.call(GetNamedPoses, "/get_named_poses",
                                               **{"tags.tags": ["drop", "trashbox_0"],
                                                  "tags.filter_mode": TagsFilter.FILTER_MODE_ALL}).poses]
r = c.call(GetNamedPoseBounds, "/get_named_pose_bounds", name="drop_trashbox_0_left")
out["pose_bounds"] = {"result": r.result.result, **box(r.bounds)}
r = c.call(GetNamedPoseBounds, "/get_named_pose_bounds", name="robot_000_start")
out["start_bounds"] = {"result": r.result.result, **box(r.bounds)}

# simulate_steps: one feedback per step, read from the action's feedback topic itself: rclpy's ActionClient drops the
# feedback that arrives after the result (it forgets the goal's feedback callback when the result comes), and a topic
# and a service are not ordered (seen: 3 of 20 feedbacks after the result under the load of a parallel test run)
action = ActionClient(c.node, SimulateSteps, "/simulate_steps")
feedback = []
c.node.create_subscription(
    SimulateSteps.Impl.FeedbackMessage, "/simulate_steps/_action/feedback",
    lambda m: feedback.append([m.feedback.completed_steps, m.feedback.remaining_steps]), QoSProfile(depth=1000))
action.wait_for_server(timeout_sec=10)
c.spin(1.0)  # let the feedback and status topics match too
goal_future = action.send_goal_async(SimulateSteps.Goal(steps=20))
c.executor.spin_until_future_complete(goal_future, timeout_sec=10)
result_future = goal_future.result().get_result_async()
c.executor.spin_until_future_complete(result_future, timeout_sec=30)
# wait for all 20 (at most 10 s), then a little more, so that a 21st would be seen
c.wait_for(lambda: len(feedback) >= 20, 10.0)
c.spin(0.3)
out["action"] = result_future.result().result.result.result
out["feedback"] = feedback


# bad input
def code(r):
    return [r.result.result, r.result.error_message]


nan = math.nan
out["bad"] = {
    "info_unknown": code(c.call(GetEntityInfo, "/get_entity_info", entity="nobody")),
    "info_agent": code(c.call(GetEntityInfo, "/get_entity_info", entity="moderator_0")),
    "set_unknown": code(c.call(SetEntityInfo, "/set_entity_info", entity="nobody")),
    "set_category": list(set_info("can_0", 3, "", []).values()),
    "set_tag_space": list(set_info("can_0", 0, "", ["two words"]).values()),
    "set_tag_empty": list(set_info("can_0", 0, "", [""]).values()),
    "bounds_unknown": code(c.call(GetEntityBounds, "/get_entity_bounds", entity="nobody")),
    "filter_nan": list(entities(**{"filters.bounds": bounds(Bounds.TYPE_BOX, (nan, 0, 0), (1, 1, 1))}).values())[:2],
    "filter_radius": list(entities(**{"filters.bounds": bounds(Bounds.TYPE_SPHERE, (0, 0, 0), (-1, 0, 0))})
                          .values())[:2],
    "filter_points": list(entities(**{"filters.bounds": bounds(Bounds.TYPE_SPHERE, (0, 0, 0))}).values())[:2],
    "filter_hull": list(entities(**{"filters.bounds": bounds(Bounds.TYPE_CONVEX_HULL, (0, 0, 0), (1, 0, 0),
                                                             (0, 1, 0))}).values())[:2],
    "filter_type": list(entities(**{"filters.bounds": bounds(7, (0, 0, 0), (1, 0, 0))}).values())[:2],
    "filter_regex": list(entities(**{"filters.filter": "can_(["}).values())[:2],
    "filter_category": list(entities(**{"filters.categories": [EntityCategory(category=3)]}).values())[:2],
    "filter_mode": list(entities(**{"filters.tags.tags": ["trash"], "filters.tags.filter_mode": 5}).values())[:2],
    "pose_unknown": code(c.call(GetNamedPoseBounds, "/get_named_pose_bounds", name="nowhere")),
}
out["after_bad"] = info("can_0")

# reset restores the world file's information
out["reset"] = c.call(ResetSimulation, "/reset_simulation").result.result
out["after_reset"] = info("can_0")
emit(out)
