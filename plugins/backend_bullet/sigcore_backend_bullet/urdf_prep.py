"""URDF documents prepared for ``pybullet.loadURDF``: meshes resolved, visuals dropped, massless links made so.

The preparations work on a copy of the world's shared parsed URDF (``World.urdf``: the file is not read again).

* ``<visual>`` elements are removed (physics needs collision geometry; visual meshes are often ``.dae``).
* Collision ``<mesh filename>`` paths are made absolute, with the MuJoCo backend's rules (relative to the
  URDF's directory; ``package://pkg/rel`` looked up in the URDF's directory and its parents).
* A link without ``<inertial>`` gets an explicit zero mass: PyBullet would otherwise give it 1 kg and a unit
  inertia (``BulletUrdfImporter``). As in the MuJoCo backend, a link on a movable joint must have an
  ``<inertial>``: the masses are the URDF's, nothing is inferred from geometry.
* Link friction from ``<gazebo reference="link"><mu1>`` (or ``<mu>``), else ``<contact><lateral_friction>``,
  is returned per link; it is applied with ``changeDynamics`` after loading.
* A person's generated URDF (:mod:`sigcore.world.body`) is loaded with its revolute joints made ``continuous``
  (held: kinematic) or ``fixed`` at their angles (dynamic: a rigid mannequin), see :func:`pose_joints`.
"""

from __future__ import annotations

import os
import tempfile
from dataclasses import dataclass

import numpy as np
from lxml import etree

from sigcore.backend import collision_urdf
from sigcore.errors import BackendError
from sigcore.geometry import quat_from_axis_angle, quat_from_rpy, quat_mul, quat_to_rpy
from sigcore.world.meshes import mesh_problem
from sigcore.world.urdf import UrdfDocument, link_friction

_ZERO_INERTIAL = ('<inertial><origin xyz="0 0 0"/><mass value="0"/>'
                  '<inertia ixx="0" ixy="0" ixz="0" iyy="0" iyz="0" izz="0"/></inertial>')


@dataclass(frozen=True)
class PreparedUrdf:
    """A URDF rewritten for PyBullet.

    Attributes:
        text: The rewritten URDF (load it from a temporary file with :func:`write_temp`).
        root: Name of the root link.
        friction: Sliding friction per link name, from ``<gazebo>`` or ``<contact>`` tags.
        massless: Links that had no ``<inertial>``.
    """

    text: str
    root: str
    friction: dict[str, float]
    massless: frozenset[str]


def prepare_urdf(urdf: UrdfDocument, what: str, floating: bool) -> PreparedUrdf:
    """Rewrite the parsed URDF ``urdf`` for PyBullet (on a copy; ``urdf`` is not changed).

    Args:
        urdf: The URDF document (``World.urdf``).
        what: The entity it belongs to, for messages, e.g. ``"robot 'robot_000'"``.
        floating: The root link moves freely (then it needs an ``<inertial>`` too).

    Raises:
        BackendError: missing collision mesh, a root link called ``world``, or a moving link without
            ``<inertial>``.
    """
    path = urdf.path
    root, roots = collision_urdf(urdf, what, mesh_problem)  # PyBullet crashes the process on some broken meshes
    if root.find("link") is None:
        raise BackendError(f"{what}: URDF {path} has no <link>")
    moving = {str(j.find("child").get("link")) for j in root.findall("joint")
              if j.get("type") != "fixed" and j.find("child") is not None}
    if floating and roots:
        moving.add(roots[0])
    massless: set[str] = set()
    for link in root.findall("link"):
        name = str(link.get("name"))
        if link.find("inertial") is None:
            if name in moving:
                raise BackendError(f"{what}: link '{name}' in {path} has no <inertial> (every link on a movable "
                                   "joint, and the root link of a robot that is not fixed, needs an <inertial> "
                                   "with positive mass and inertia; masses come only from <inertial>)")
            link.insert(0, etree.fromstring(_ZERO_INERTIAL))
            massless.add(name)
    first = roots[0] if roots else str(root.find("link").get("name"))
    return PreparedUrdf(etree.tostring(root, encoding="unicode"), first, link_friction(root), frozenset(massless))


def write_temp(text: str) -> str:
    """Write ``text`` to a new temporary ``.urdf`` file and return its path (the caller deletes it)."""
    fd, name = tempfile.mkstemp(suffix=".urdf", prefix="sigcore_bullet_")
    with os.fdopen(fd, "w") as f:
        f.write(text)
    return name


def pose_joints(text: str, angles: dict[str, float] | None) -> str:
    """A person's prepared URDF ``text`` with its revolute joints made kinematic or rigid.

    Args:
        text: The prepared URDF (:attr:`PreparedUrdf.text`).
        angles: ``None``: every revolute joint becomes ``continuous`` (no limit constraint: a held person's angles
            are set, never simulated, and PyBullet's limit rows cost more than its dynamics). Otherwise each
            revolute joint becomes ``fixed`` at its angle [rad] here (0 if absent): the origin's rotation is
            composed with the rotation about the joint's axis, so every link keeps the pose it has at that angle
            and the body is one rigid multibody (a mannequin).
    """
    root = etree.fromstring(text.encode())
    for joint in root.findall("joint"):
        if joint.get("type") not in ("revolute", "continuous"):
            continue
        if angles is None:
            joint.set("type", "continuous")
            for limit in joint.findall("limit"):
                joint.remove(limit)
            continue
        origin = joint.find("origin")
        if origin is None:
            origin = etree.SubElement(joint, "origin")
        axis_element = joint.find("axis")
        axis = _floats(axis_element.get("xyz") if axis_element is not None else None, (1.0, 0.0, 0.0))
        rpy = _floats(origin.get("rpy"), (0.0, 0.0, 0.0))
        turned = quat_mul(quat_from_rpy(*rpy), quat_from_axis_angle(np.array(axis), angles.get(str(joint.get("name")),
                                                                                                 0.0)))
        origin.set("rpy", " ".join(repr(float(v)) for v in quat_to_rpy(turned)))
        joint.set("type", "fixed")
        for child in joint.findall("axis") + joint.findall("limit") + joint.findall("dynamics"):
            joint.remove(child)
    return etree.tostring(root, encoding="unicode")


def _floats(text: str | None, default: tuple[float, float, float]) -> tuple[float, float, float]:
    values = [float(v) for v in text.split()] if text else []
    return (values[0], values[1], values[2]) if len(values) == 3 else default
