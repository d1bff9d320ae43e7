"""Handlers of the API table: validate, call the agent handle, answer.

Each handler is ``handler(sim, agent, request) -> dict | None``. ``request`` is already validated against its
type; handlers check names and values through the handle, which raises ``ApiError`` for anything invalid.
In sig_ros, an empty ``name`` means "this agent"; any other value targets that entity.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from ..agent.exceptions import ApiError
from ..agent.handle import SimObj
from ..agent.robot import RobotObj
from ..text import quote

if TYPE_CHECKING:
    from ..sim.simulation import Simulation


def _target(sim: Simulation, agent: str, name: str) -> SimObj:
    return sim.agent(name or agent)


def _robot(sim: Simulation, agent: str, name: str = "") -> RobotObj:
    return sim.robot(name or agent)


def _pos(v: Any) -> dict[str, float]:
    return {"pos_x": float(v[0]), "pos_y": float(v[1]), "pos_z": float(v[2])}


# ------------------------------------------------------------------ topics the agent subscribes to
def set_wheel(sim: Simulation, agent: str, m: Any) -> None:
    _robot(sim, agent).set_wheel(m.wheel_radius, m.wheel_distance)


def set_wheel_velocity(sim: Simulation, agent: str, m: Any) -> None:
    _robot(sim, agent).set_wheel_velocity(m.left_wheel, m.right_wheel)


def set_joint_velocity(sim: Simulation, agent: str, m: Any) -> None:
    _robot(sim, agent).set_joint_velocity(m.joint_name, m.angular_velocity, m.max)


def set_joint_angle(sim: Simulation, agent: str, m: Any) -> None:
    person = m.name or agent
    if person in sim.entities.people.names:  # a person's joints are posed kinematically (sigcore.sim.people)
        sim.entities.people.set_joints(person, {m.joint_name: m.angle})
        return
    _robot(sim, agent, m.name).set_joint_angle(m.joint_name, m.angle)


def set_joint_target(sim: Simulation, agent: str, m: Any) -> None:
    _robot(sim, agent, m.name).set_joint_target(m.joint_name, m.angle)


def set_joint_quaternion(sim: Simulation, agent: str, m: Any) -> None:
    person = m.name or agent
    if person in sim.entities.people.names:
        people = sim.entities.people
        people.set_joints(person, {m.joint_name: people.joint_quaternion(person, m.joint_name,
                                                                         (m.qw, m.qx, m.qy, m.qz), m.offset)})
        return
    _robot(sim, agent, m.name).set_joint_quaternion(m.joint_name, (m.qw, m.qx, m.qy, m.qz), m.offset)


def add_joint_torque(sim: Simulation, agent: str, m: Any) -> None:
    _robot(sim, agent, m.name).add_joint_torque(m.joint_name, m.torque)


def release_obj(sim: Simulation, agent: str, m: Any) -> None:
    robot = _robot(sim, agent)
    robot.release(robot.gripper_for_arm(m.arm))


def vector(method: str) -> Callable[[Simulation, str, Any], None]:
    """Handler calling ``handle.<method>((x, y, z))`` on the target entity."""

    def handler(sim: Simulation, agent: str, m: Any) -> None:
        getattr(_target(sim, agent, m.name), method)((m.x, m.y, m.z))

    handler.__name__ = method
    return handler


def force_at(method: str) -> Callable[[Simulation, str, Any], None]:
    """Handler calling ``handle.<method>(force, point)`` on the target entity."""

    def handler(sim: Simulation, agent: str, m: Any) -> None:
        getattr(_target(sim, agent, m.name), method)((m.x, m.y, m.z), (m.pos_x, m.pos_y, m.pos_z))

    handler.__name__ = method
    return handler


def add_force_to_parts(sim: Simulation, agent: str, m: Any) -> None:
    _target(sim, agent, m.name).add_force_to_part(m.part, (m.x, m.y, m.z))


def set_rotation(sim: Simulation, agent: str, m: Any) -> None:
    _target(sim, agent, m.name).set_rotation((m.qw, m.qx, m.qy, m.qz))


def set_axis_and_angle(sim: Simulation, agent: str, m: Any) -> None:
    _target(sim, agent, m.name).set_axis_and_angle((m.axis_x, m.axis_y, m.axis_z), m.angle)


def mode(which: str) -> Callable[[Simulation, str, Any], None]:
    """Handler switching the ``gravity``, ``dynamics`` or ``collision`` mode of the target entity."""

    def handler(sim: Simulation, agent: str, m: Any) -> None:
        target = _target(sim, agent, m.name)
        {"gravity": target.set_gravity_mode, "dynamics": target.set_dynamics_mode,
         "collision": target.set_collision_enable}[which](m.flag)

    handler.__name__ = f"set_{which}_mode"
    return handler


def set_mass(sim: Simulation, agent: str, m: Any) -> None:
    _target(sim, agent, m.name).set_mass(m.mass)


def set_owner(sim: Simulation, agent: str, m: Any) -> None:
    _target(sim, agent, m.name).set_owner(m.part, m.owner)


def send_msg(sim: Simulation, agent: str, m: Any) -> None:
    if m.to:
        sim.send_msg(agent, m.to, m.content)
    else:
        sim.broadcast_msg(agent, m.content)


# ------------------------------------------------------------------ services
def get_time(sim: Simulation, agent: str, m: Any) -> dict[str, Any]:
    return {"time": sim.time}


def get_entities(sim: Simulation, agent: str, m: Any) -> dict[str, Any]:
    names = list(sim.entities)
    return {"entities_names": names, "length": len(names)}


def get_obj_position(sim: Simulation, agent: str, m: Any) -> dict[str, Any]:
    return _pos(_target(sim, agent, m.name).position())


def get_parts_position(sim: Simulation, agent: str, m: Any) -> dict[str, Any]:
    return _pos(_target(sim, agent, m.name).part_position(m.part))


def get_joint_position(sim: Simulation, agent: str, m: Any) -> dict[str, Any]:
    return _pos(_robot(sim, agent, m.name).joint_position(m.joint_name))


def get_rotation(sim: Simulation, agent: str, m: Any) -> dict[str, Any]:
    q = _target(sim, agent, m.name).rotation()
    return {"qw": float(q[0]), "qx": float(q[1]), "qy": float(q[2]), "qz": float(q[3])}


def get_angle_rotation(sim: Simulation, agent: str, m: Any) -> dict[str, Any]:
    return {"angle": SimObj.angle_to_axis(m.axis, (m.x, m.y, m.z))}


def get_joint_angle(sim: Simulation, agent: str, m: Any) -> dict[str, Any]:
    return {"angle": _robot(sim, agent, m.name).joint_angle(m.name_arm)}


def get_all_joint_angles(sim: Simulation, agent: str, m: Any) -> dict[str, Any]:
    target = _target(sim, agent, m.name)
    angles = target.all_joint_angles() if isinstance(target, RobotObj) else {}
    return {"joint_name": list(angles), "angle": list(angles.values()), "length": len(angles)}


def get_mass(sim: Simulation, agent: str, m: Any) -> dict[str, Any]:
    return {"mass": _target(sim, agent, m.name).mass()}


def get_angular_velocity(sim: Simulation, agent: str, m: Any) -> dict[str, Any]:
    w = _target(sim, agent, m.name).angular_velocity()
    return {"v_x": float(w[0]), "v_y": float(w[1]), "v_z": float(w[2])}


def get_collision_state(sim: Simulation, agent: str, m: Any) -> dict[str, Any]:
    return {"collision_state": _target(sim, agent, m.name).collision_state(m.part or "main")}


def grasp_obj(sim: Simulation, agent: str, m: Any) -> dict[str, Any]:
    robot = _robot(sim, agent)
    robot.grasp(robot.gripper_for_arm(m.part) if m.part in ("left", "right") else m.part, m.obj)
    return {"ok": True}


def is_grasped(sim: Simulation, agent: str, m: Any) -> dict[str, Any]:
    return {"answer": _target(sim, agent, m.name).is_grasped()}


def get_collision_state_of_main_part(sim: Simulation, agent: str, m: Any) -> dict[str, Any]:
    return {"collision_state": _target(sim, agent, m.name).collision_state("main")}


def service_name(sim: Simulation, name: str) -> str:
    """The registered viewer service ``name`` designates, compared ignoring case (sig_ros's ``Referee`` is
    sigcore's ``referee``); an exact match wins.

    Raises:
        ApiError: no service of that name (the message lists the services), or several that differ only in case.
    """
    if name in sim.features.services:
        return name
    matches = [s for s in sim.features.services if s.casefold() == name.casefold()]
    if len(matches) == 1:
        return matches[0]
    if matches:
        raise ApiError(f"service name {quote(name)} matches {', '.join(sorted(matches))}, which differ only in case; "
                       "give the exact name")
    services = ', '.join(sorted(sim.features.services)) or 'none'
    raise ApiError(f"no service {quote(name)}; services: {services} (names are "
                   "compared ignoring case)")


def check_service(sim: Simulation, agent: str, m: Any) -> dict[str, Any]:
    return {"connected": sim.features.connected(agent, service_name(sim, m.service_name))}


def connect_to_service(sim: Simulation, agent: str, m: Any) -> dict[str, Any]:
    sim.features.connect(agent, service_name(sim, m.service_name))
    return {"connected": True}


def send_msg_to_srv(sim: Simulation, agent: str, m: Any) -> dict[str, Any]:
    name = service_name(sim, m.name)
    if not sim.features.connected(agent, name):
        raise ApiError(f"'{agent}' is not connected to service '{name}'; call {agent}_connect_to_service first")
    sim.features.services[name](agent, m.msg)
    return {"ok": True}


# ------------------------------------------------------------------ cameras (SIGVerse's captureView, distanceSensor)
def capture_view(sim: Simulation, agent: str, m: Any) -> dict[str, Any]:
    from ..sim.camera import image_fields

    frame = sim.cameras.grab(sim.cameras.find(agent, m.camera))
    header = {"stamp": frame.stamp_ns, "frame_id": frame.frame}
    return {"image": image_fields(header, frame.rgb, "rgb8") if frame.rgb is not None else {},
            "depth": image_fields(header, frame.depth, "32FC1") if frame.depth is not None else {},
            "camera_info": {"header": header, **frame.info}}


def distance_sensor(sim: Simulation, agent: str, m: Any) -> dict[str, Any]:
    return {"distance": sim.cameras.distance(sim.cameras.find(agent, m.camera))}
