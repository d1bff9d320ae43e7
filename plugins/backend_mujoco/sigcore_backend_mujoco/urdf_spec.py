"""URDF documents -> MuJoCo specs: mesh paths resolved, visuals dropped, Gazebo friction read.

MuJoCo's URDF importer is used as is, on a copy of the world's shared parsed URDF (``World.urdf``: the file is not
read again), with three preparations:

* ``<visual>`` elements are removed: physics needs collision geometry only, and visual meshes are often in
  formats MuJoCo cannot read (``.dae``).
* Every collision ``<mesh filename>`` is made absolute: relative paths are taken relative to the URDF's
  directory, ``package://pkg/rel`` is looked up in the URDF's directory and its parents (``pkg/rel`` or
  ``rel`` below a directory named ``pkg``), ``file://`` is stripped. A missing mesh is a :class:`BackendError`
  naming the entity.
* ``<gazebo reference="link"><mu1>`` (or ``<mu>``), else PyBullet's ``<contact><lateral_friction>`` in the
  link, gives that link's sliding friction: the conventions ROS users already use for slippery casters.

The spec keeps every link as a body (``fusestatic`` off: fixed links such as a lidar or a hand are parts) and
takes masses only from ``<inertial>`` (``inertiafromgeom`` false), as URDF means, Pinocchio and PyBullet read
them.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
from lxml import etree

from sigcore.backend import collision_urdf
from sigcore.errors import BackendError
from sigcore.world.urdf import UrdfDocument, link_friction


@dataclass(frozen=True)
class LoadedUrdf:
    """A URDF read into a MuJoCo spec, ready to be attached into the world spec.

    Attributes:
        spec: The child spec; its first body is the root link.
        root: Name of the root link.
        friction: Sliding friction per link name, from ``<gazebo>`` or ``<contact>`` tags.
    """

    spec: mujoco.MjSpec
    root: str
    friction: dict[str, float]


def load_urdf(urdf: UrdfDocument, what: str, scale: float = 1.0) -> LoadedUrdf:
    """Turn the parsed URDF ``urdf`` into a MuJoCo spec (it works on a copy; ``urdf`` is not changed).

    Args:
        urdf: The URDF document (``World.urdf``).
        what: The entity it belongs to, for messages, e.g. ``"robot 'robot_000'"``.
        scale: Every length of the model multiplied by this (an object's ``scale``, as PyBullet's
            ``globalScaling``): origins, primitive sizes, mesh scales, prismatic limits; inertia by its square.

    Raises:
        BackendError: missing collision mesh, a root link called ``world``, or a URDF MuJoCo rejects.
    """
    path = urdf.path
    root, _ = collision_urdf(urdf, what)
    if scale != 1.0:
        _scale(root, scale)
    friction = link_friction(root)
    try:
        spec = mujoco.MjSpec.from_string(etree.tostring(root, encoding="unicode"))
    except ValueError as e:
        raise BackendError(f"{what}: MuJoCo cannot read URDF {path}: {_first_line(e)}") from None
    spec.compiler.fusestatic = False
    spec.compiler.discardvisual = True
    spec.compiler.inertiafromgeom = mujoco.mjtInertiaFromGeom.mjINERTIAFROMGEOM_FALSE
    first = spec.worldbody.first_body()
    if first is None:
        raise BackendError(f"{what}: URDF {path} has no link MuJoCo could import")
    return LoadedUrdf(spec, str(first.name), friction)








_LENGTHS = {"origin": ("xyz",), "box": ("size",), "cylinder": ("radius", "length"), "sphere": ("radius",)}


def _scale(root: etree._Element, s: float) -> None:
    """Multiply every length of the parsed URDF ``root`` by ``s`` (in place, on the loader's copy)."""

    def times(text: str, factor: float) -> str:
        return " ".join(repr(float(v) * factor) for v in text.split())

    for element in root.iter("origin", "box", "cylinder", "sphere"):
        for attribute in _LENGTHS[str(element.tag)]:
            if element.get(attribute) is not None:
                element.set(attribute, times(str(element.get(attribute)), s))
    for mesh in root.iter("mesh"):
        mesh.set("scale", times(str(mesh.get("scale", "1 1 1")), s))
    for inertia in root.iter("inertia"):
        for attribute in ("ixx", "ixy", "ixz", "iyy", "iyz", "izz"):
            if inertia.get(attribute) is not None:
                inertia.set(attribute, times(str(inertia.get(attribute)), s * s))
    for joint in root.iter("joint"):
        limit = joint.find("limit")
        if joint.get("type") == "prismatic" and limit is not None:
            for attribute in ("lower", "upper"):
                if limit.get(attribute) is not None:
                    limit.set(attribute, times(str(limit.get(attribute)), s))


def _first_line(error: Exception) -> str:
    return " ".join(str(error).split())
