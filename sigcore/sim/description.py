"""What the core publishes about the world's appearance: each robot's ``robot_description`` and ``/sigcore/scene``.

Both are latched, declared through the publication contract (:mod:`sigcore.publish`), so every transport gets them
and late subscribers receive the last value:

* ``/<robot>/robot_description`` (``std_msgs/msg/String``) for every robot, and ``/robot_description`` too when the
  world has exactly one robot (what ``robot_state_publisher`` users expect): the robot's URDF with every
  ``<mesh filename>`` rewritten to a ``file://`` absolute path, and with several robots every link name (and the
  joints' ``parent``/``child``, Gazebo ``reference``) prefixed ``<robot>/`` so that the names equal the TF frames;
  joint names stay as they are (they match ``/<robot>/joint_states``). A URDF with nothing to rewrite is sent as
  its file's text. Every ``<capsule>`` (the engines' extension, which rviz's URDF reader refuses) becomes a
  ``<cylinder>`` and two ``<sphere>`` elements.
* ``/<person>/robot_description`` for every human: its generated URDF (:mod:`sigcore.world.body`) with the link
  and joint names of REP-155 for body ``<person>``: links ``<link>_<person>`` (the TF frames; its feet ``main``:
  ``<person>``), joints ``<joint>_<person>``, as ros4hri's ``human_description`` names them.
* ``/sigcore/scene`` (``visualization_msgs/msg/MarkerArray``): a ``DELETEALL`` marker, then per entity (``ns`` = its
  name, ``id`` from 0) one marker per visual of the scene description (:class:`sigcore.scene.Scene`) in its TF frame:
  ``CUBE``, ``SPHERE``, ``CYLINDER`` (a capsule: a cylinder and two spheres), ``MESH_RESOURCE`` (``file://`` URI,
  the visual's colour); ``frame_locked``, stamp 0 (a viewer draws them at the frame's latest transform).
  Published when declared and again after every :meth:`Scene.changed`.
"""

from __future__ import annotations

import copy
import logging
from typing import TYPE_CHECKING, Any

import numpy as np
from lxml import etree

from ..geometry import quat_from_rpy, quat_rotate
from ..publish import Publication, Publisher
from ..scene import Scene
from ..world.body import ROOT
from ..world.models import Human, Robot, World
from ..world.urdf import resolve_mesh
from ..world.visuals import Visual

if TYPE_CHECKING:
    from .simulation import Simulation

log = logging.getLogger("sigcore")

SCENE = Publication("/sigcore/scene", "visualization_msgs/msg/MarkerArray", "latched",
                    "every entity's visual geometry as markers in its TF frame (republished when the scene changes)")

# visualization_msgs/msg/Marker constants
CUBE, SPHERE, CYLINDER, MESH_RESOURCE = 1, 2, 3, 10
ADD, DELETEALL = 0, 3


def description_topics(world: World) -> dict[str, str]:
    """Topic -> robot or person of every ``robot_description`` publication of ``world``."""
    robots = [a.name for a in world.agents if isinstance(a, Robot)]
    topics = {f"/{a.name}/robot_description": a.name for a in world.agents if isinstance(a, Robot | Human)}
    if len(robots) == 1:
        topics["/robot_description"] = robots[0]
    return topics


def robot_description(world: World, robot: str, prefix: str = "") -> str:
    """The URDF text of ``robot`` for ``robot_description``: meshes as ``file://`` absolute paths, link names
    prefixed with ``prefix`` (``""`` with one robot, ``"<robot>/"`` with several), capsules as cylinders and
    spheres; a person's links and joints named as REP-155 names them (``head_<person>``).

    A mesh that cannot be resolved keeps its filename (logged). The file's text unchanged if nothing is rewritten.
    """
    document = world.urdf(robot)
    tree = copy.deepcopy(document.root.getroottree())  # the shared document is never changed
    root = tree.getroot()
    rewritten = _no_capsules(root)
    if isinstance(world.agent(robot), Human):
        _rep155_names(root, robot)
        return etree.tostring(tree, encoding="unicode")
    for mesh in root.iter("mesh"):
        filename = str(mesh.get("filename", ""))
        path = resolve_mesh(filename, document.path.parent)
        if path is None:
            log.warning("robot_description of '%s': mesh %r not found from %s; left as it is", robot, filename,
                        document.path.parent)
            continue
        uri = f"file://{path}"
        if uri != filename:
            mesh.set("filename", uri)
            rewritten = True
    if prefix:
        links = set(document.model.links)
        for link in root.findall("link"):
            link.set("name", prefix + str(link.get("name")))
        for element in [*root.findall("joint/parent"), *root.findall("joint/child")]:
            element.set("link", prefix + str(element.get("link")))
        for gazebo in root.findall("gazebo"):
            if gazebo.get("reference") in links:
                gazebo.set("reference", prefix + str(gazebo.get("reference")))
        rewritten = True
    return etree.tostring(tree, encoding="unicode") if rewritten else document.text


def _no_capsules(root: etree._Element) -> bool:
    """Replace each ``<capsule radius length>`` of a visual or collision by a ``<cylinder>`` and two ``<sphere>``
    elements at its ends (copies of the element with their own geometry); whether there was any."""
    found = False
    for capsule in list(root.iter("capsule")):
        geometry = capsule.getparent()
        element = geometry.getparent() if geometry is not None else None
        if element is None or element.getparent() is None:
            continue
        found = True
        radius, length = float(capsule.get("radius", "0")), float(capsule.get("length", "0"))
        capsule.tag = "cylinder"
        origin = element.find("origin")
        xyz = np.array([float(v) for v in (origin.get("xyz", "0 0 0") if origin is not None else "0 0 0").split()])
        rpy = [float(v) for v in (origin.get("rpy", "0 0 0") if origin is not None else "0 0 0").split()]
        axis = quat_rotate(quat_from_rpy(*rpy), np.array([0.0, 0.0, 1.0]))
        at = element.getparent().index(element)
        for sign in (1.0, -1.0):
            end = copy.deepcopy(element)
            for child in list(end.find("geometry")):
                end.find("geometry").remove(child)
            etree.SubElement(end.find("geometry"), "sphere", radius=repr(radius))
            centre = xyz + sign * (length / 2) * axis
            end_origin = end.find("origin")
            if end_origin is None:
                end_origin = etree.SubElement(end, "origin")
            end_origin.set("xyz", " ".join(repr(float(v)) for v in centre))
            element.getparent().insert(at + 1, end)
    return found


def _rep155_names(root: etree._Element, person: str) -> None:
    """Name a person's links ``<link>_<person>`` (its root, the feet: ``<person>``) and joints
    ``<joint>_<person>``, and its materials likewise (REP-155; several people in one TF tree stay apart)."""

    def link_name(link: str) -> str:
        return person if link == ROOT else f"{link}_{person}"

    root.set("name", person)
    for link in root.findall("link"):
        link.set("name", link_name(str(link.get("name"))))
    for joint in root.findall("joint"):
        joint.set("name", f"{joint.get('name')}_{person}")
        for end in (joint.find("parent"), joint.find("child")):
            if end is not None:
                end.set("link", link_name(str(end.get("link"))))
    for material in root.iter("material"):
        material.set("name", f"{material.get('name')}_{person}")


def _xyz(v: Any) -> dict[str, float]:
    return {"x": float(v[0]), "y": float(v[1]), "z": float(v[2])}


def _marker(ns: str, number: int, visual: Visual, kind: int, xyz: Any, scale: Any) -> dict[str, Any]:
    w, x, y, z = visual.wxyz
    r, g, b, a = visual.color
    marker: dict[str, Any] = {
        "header": {"stamp": 0, "frame_id": visual.frame}, "ns": ns, "id": number, "type": kind, "action": ADD,
        "pose": {"position": _xyz(xyz), "orientation": {"x": x, "y": y, "z": z, "w": w}},
        "scale": _xyz(scale), "color": {"r": r, "g": g, "b": b, "a": a}, "frame_locked": True}
    if kind == MESH_RESOURCE:
        marker["mesh_resource"] = f"file://{visual.mesh}"
        marker["mesh_use_embedded_materials"] = False
    return marker


def visual_markers(ns: str, first_id: int, visual: Visual) -> list[dict[str, Any]]:
    """The ``visualization_msgs/Marker`` fields of one visual (ids from ``first_id``; a capsule gives three)."""
    s = visual.size
    if visual.shape == "box":
        return [_marker(ns, first_id, visual, CUBE, visual.xyz, s)]
    if visual.shape == "sphere":
        return [_marker(ns, first_id, visual, SPHERE, visual.xyz, (2 * s[0],) * 3)]
    if visual.shape == "mesh":
        return [_marker(ns, first_id, visual, MESH_RESOURCE, visual.xyz, s)]
    out = [_marker(ns, first_id, visual, CYLINDER, visual.xyz, (2 * s[0], 2 * s[0], s[1]))]
    if visual.shape == "capsule":
        axis = quat_rotate(np.array(visual.wxyz), np.array([0.0, 0.0, s[1] / 2]))
        for k, sign in enumerate((1.0, -1.0)):
            out.append(_marker(ns, first_id + 1 + k, visual, SPHERE, np.array(visual.xyz) + sign * axis,
                               (2 * s[0],) * 3))
    return out


def scene_markers(scene: Scene) -> dict[str, Any]:
    """The ``visualization_msgs/MarkerArray`` fields of ``scene``: ``DELETEALL``, then every entity's markers."""
    markers: list[dict[str, Any]] = [{"action": DELETEALL}]
    for name, entity in scene.entities.items():
        number = 0
        for visual in entity.visuals:
            made = visual_markers(name, number, visual)
            markers.extend(made)
            number += len(made)
    return {"markers": markers}


class DescriptionTopics:
    """Declares and publishes ``robot_description`` and ``/sigcore/scene`` for ``sim`` (done on construction;
    the scene is republished after every :meth:`Scene.changed`).

    Args:
        sim: The simulation (its ``frames`` and ``scene`` made).
    """

    def __init__(self, sim: Simulation) -> None:
        self._sim = sim
        self._topics: dict[str, list[str]] = {}
        """robot -> its robot_description topics."""
        for topic, robot in description_topics(sim.world).items():
            self._declare(robot, topic)
        self._scene: Publisher = sim.publications.declare(SCENE)
        sim.events.subscribe("scene", self.publish_scene)
        self.publish_scene(sim.scene)

    def _declare(self, robot: str, topic: str) -> None:
        sim = self._sim
        person = isinstance(sim.world.agent(robot), Human)
        text = robot_description(sim.world, robot, "" if person else sim.frames.prefix(robot))
        pub = sim.publications.declare(Publication(
            topic, "std_msgs/msg/String", "latched",
            f"the URDF of {sim.world.agent(robot).kind} '{robot}' (file:// meshes, link names = TF frames)",
            agent=""))
        pub.publish({"data": text})
        self._topics.setdefault(robot, []).append(topic)

    def add(self, robot: str, namespace: str = "") -> None:
        """A robot or person spawned while running: ``<namespace>/<robot>/robot_description`` (never the world's
        ``/robot_description``, which stays the first robot's)."""
        self._declare(robot, f"{namespace}/{robot}/robot_description")

    def remove(self, robot: str) -> None:
        """A robot or person deleted while running: its topics are withdrawn (nothing if it had none)."""
        for topic in self._topics.pop(robot, []):
            self._sim.publications.withdraw(topic)

    def publish_scene(self, scene: Scene) -> None:
        """Push ``scene`` as markers on ``/sigcore/scene``."""
        self._scene.publish(scene_markers(scene))
