"""A person's body: the one owner of its links, joints, shapes, masses and colours, and of its generated URDF.

Every ``<human>`` is an articulated humanoid with REP-155's link and joint names and axes (the names ROS's human
tools read: ``body``, ``waist``, ``torso``, ``head``, ``l_shoulder``, ``l_elbow``, ``l_wrist``, ``l_hip``,
``l_knee``, ``l_ankle`` and their ``r_`` twins; joints ``waist``, ``r_head``/``y_head``/``p_head``,
``l_y_shoulder``/``l_p_shoulder``/``l_r_shoulder``, ``l_elbow``, ``l_y_hip``/``l_p_hip``/``l_r_hip``, ``l_knee``),
sized from its ``height`` with REP-155's proportions (a unit of ``height / 7.5``: upper arm 1.6, forearm 1, torso
2.75, hips 1.2 apart, thigh 1.5, shank 2, head radius 0.5), with two additions a walking body needs:

* a root link ``main`` at the feet (the person's pose in the world file, ``get_pose``), with ``body`` (the pelvis,
  REP-155's root) fixed above it at hip height;
* an ``l_ankle``/``r_ankle`` joint that pitches the foot (REP-155 fixes the ankle): a foot stays flat on the floor
  while the shank swings over it.

Collision shapes are capsules (limbs, torso, pelvis), spheres (head, hands) and boxes (feet); each shank is a
capsule of radius 0.06 m and each thigh 0.075 m (at 1.7 m; they scale with the height), so that a planar lidar at
0.2-0.3 m sees two legs 0.15 m apart. Masses follow a standard anthropometric split of the person's ``mass``.

:func:`human_urdf` writes it as URDF text with capsule geometry (both engines' URDF importers read ``<capsule>``);
``robot_description`` rewrites each capsule as a cylinder and two spheres, which every URDF reader knows.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from lxml import etree

Color = tuple[float, float, float, float]

SKIN: Color = (0.9, 0.7, 0.55, 1.0)
SHIRT: Color = (0.25, 0.45, 0.75, 1.0)
TROUSERS: Color = (0.22, 0.22, 0.3, 1.0)
SHOES: Color = (0.15, 0.1, 0.08, 1.0)

ROOT = "main"
"""The root link: the person's frame on the floor between the feet (x forward, z up)."""

_VIRTUAL_MASS = 0.01
"""[kg] of each link that only carries a joint (REP-155's ``y_``/``p_`` links between the axes of a shoulder)."""


@dataclass(frozen=True)
class Shape:
    """One collision and visual shape of a link.

    Attributes:
        kind: ``capsule``, ``sphere`` or ``box``; a capsule lies along its frame's z axis.
        size: capsule: (radius, length of the cylindrical part); sphere: (radius,); box: full lengths (3,) [m].
        xyz: Its centre in the link frame [m].
        rpy: Its orientation in the link frame [rad].
        color: r, g, b, a.
    """

    kind: str
    size: tuple[float, ...]
    xyz: tuple[float, float, float]
    rpy: tuple[float, float, float]
    color: Color


@dataclass(frozen=True)
class Link:
    """A link: its shapes and its share of the mass (the fraction of the person's mass)."""

    name: str
    shapes: tuple[Shape, ...]
    mass_share: float


@dataclass(frozen=True)
class Joint:
    """A joint: ``revolute`` (with axis and limits) or ``fixed``; ``xyz`` is the child's origin in the parent's."""

    name: str
    type: str
    parent: str
    child: str
    xyz: tuple[float, float, float]
    axis: tuple[float, float, float] = (1.0, 0.0, 0.0)
    lower: float = 0.0
    upper: float = 0.0


@dataclass(frozen=True)
class Body:
    """A person's body, links and joints in tree order (each joint's parent comes before its child).

    Attributes:
        height: [m], floor to the top of the head.
        mass: [kg].
        links: The links, ``main`` first.
        joints: The joints.
        hip_height: Height of ``body`` (the hips) above the feet when standing [m].
        thigh: Hip to knee [m].
        shank: Knee to ankle [m].
        ankle_height: Ankle above the sole [m].
        foot_length: [m].
    """

    height: float
    mass: float
    links: tuple[Link, ...]
    joints: tuple[Joint, ...]
    hip_height: float
    thigh: float
    shank: float
    ankle_height: float
    foot_length: float

    @property
    def movable_joints(self) -> tuple[Joint, ...]:
        """The revolute joints, in order."""
        return tuple(j for j in self.joints if j.type == "revolute")


def human_body(height: float, mass: float) -> Body:
    """The body of a person ``height`` [m] tall weighing ``mass`` [kg] (see the module docstring)."""
    u = height / 7.5
    s = height / 1.7  # radii scale with the height, from an adult of 1.7 m
    ankle = 0.045 * height
    thigh, shank = 1.5 * u, 2.0 * u - ankle
    hip_height = 3.5 * u
    torso, neck, head_r = 2.75 * u, 0.25 * u, 0.5 * u
    upper_arm, forearm = 1.6 * u, 1.0 * u
    shoulder_y, hip_y = 0.8 * u, 0.6 * u
    foot_length, foot_width = 0.15 * height, 0.055 * height
    r_pelvis, r_torso = 0.11 * s, 0.13 * s
    r_thigh, r_shank, r_upper, r_fore, r_hand = 0.075 * s, 0.06 * s, 0.045 * s, 0.038 * s, 0.045 * s
    flat = (0.0, 0.0, 0.0)
    across = (math.pi / 2, 0.0, 0.0)  # a capsule along y

    def limb(radius: float, length: float, color: Color) -> Shape:
        """A capsule hanging from the link's origin down to ``length`` below it."""
        return Shape("capsule", (radius, max(length - 2 * radius, 1e-3)), (0.0, 0.0, -length / 2), flat, color)

    links = [
        Link(ROOT, (), 0.0),
        Link("body", (Shape("capsule", (r_pelvis, max(2 * hip_y - r_pelvis, 1e-3)), (0.0, 0.0, 0.04 * s),
                            across, TROUSERS),), 0.142),
        Link("waist", (), 0.0),
        Link("torso", (Shape("capsule", (r_torso, torso - 2 * r_torso - 0.02 * s), (0.0, 0.0, -torso / 2 + 0.01 * s),
                             flat, SHIRT),), 0.355),
        Link("r_head", (), 0.0), Link("y_head", (), 0.0), Link("p_head", (), 0.0),
        Link("head", (Shape("sphere", (head_r,), (-head_r / 2, 0.0, 0.0), flat, SKIN),), 0.081),
    ]
    joints = [
        Joint("body", "fixed", ROOT, "body", (0.0, 0.0, hip_height)),
        Joint("waist", "revolute", "body", "waist", (0.0, 0.0, 0.0), (0.0, 1.0, 0.0), -0.2, 1.0),
        Joint("torso", "fixed", "waist", "torso", (0.0, 0.0, torso)),
        Joint("r_head", "revolute", "torso", "r_head", (0.0, 0.0, neck), (1.0, 0.0, 0.0), -1.0, 1.0),
        Joint("y_head", "revolute", "r_head", "y_head", flat, (0.0, 0.0, 1.0), -1.4, 1.4),
        Joint("p_head", "revolute", "y_head", "p_head", flat, (0.0, -1.0, 0.0), -1.5, 1.5),
        Joint("head", "fixed", "p_head", "head", (head_r / 2, 0.0, head_r)),
    ]
    for side, reflect in (("l", 1.0), ("r", -1.0)):
        links += [
            Link(f"{side}_y_shoulder", (), 0.0), Link(f"{side}_p_shoulder", (), 0.0),
            Link(f"{side}_shoulder", (limb(r_upper, upper_arm, SHIRT),), 0.028),
            Link(f"{side}_elbow", (limb(r_fore, forearm, SKIN),), 0.016),
            Link(f"{side}_wrist", (Shape("sphere", (r_hand,), (0.0, 0.0, -r_hand), flat, SKIN),), 0.006),
        ]
        joints += [
            Joint(f"{side}_y_shoulder", "revolute", "torso", f"{side}_y_shoulder", (0.0, reflect * shoulder_y, 0.0),
                  (0.0, 0.0, -reflect), -1.7, 1.7),
            Joint(f"{side}_p_shoulder", "revolute", f"{side}_y_shoulder", f"{side}_p_shoulder", flat,
                  (reflect, 0.0, 0.0), -0.4, 3.3),
            Joint(f"{side}_r_shoulder", "revolute", f"{side}_p_shoulder", f"{side}_shoulder", flat,
                  (0.0, 0.0, reflect), -1.7, 1.7),
            Joint(f"{side}_elbow", "revolute", f"{side}_shoulder", f"{side}_elbow", (0.0, 0.0, -upper_arm),
                  (0.0, -1.0, 0.0), 0.0, 2.5),
            Joint(f"{side}_wrist", "fixed", f"{side}_elbow", f"{side}_wrist", (0.0, 0.0, -forearm)),
        ]
    for side, reflect in (("l", 1.0), ("r", -1.0)):
        foot = Shape("box", (foot_length, foot_width, ankle), (0.3 * foot_length, 0.0, -ankle / 2), flat, SHOES)
        links += [
            Link(f"{side}_y_hip", (), 0.0), Link(f"{side}_p_hip", (), 0.0),
            Link(f"{side}_hip", (limb(r_thigh, thigh, TROUSERS),), 0.1),
            Link(f"{side}_knee", (limb(r_shank, shank, TROUSERS),), 0.0465),
            Link(f"{side}_ankle", (foot,), 0.0145),
        ]
        joints += [
            Joint(f"{side}_y_hip", "revolute", "body", f"{side}_y_hip", (0.0, reflect * hip_y, 0.0),
                  (0.0, 0.0, -1.0), -0.6, 0.6),
            Joint(f"{side}_p_hip", "revolute", f"{side}_y_hip", f"{side}_p_hip", flat, (reflect, 0.0, 0.0),
                  -0.4, 1.2),
            Joint(f"{side}_r_hip", "revolute", f"{side}_p_hip", f"{side}_hip", flat, (0.0, -1.0, 0.0), -0.6, 1.6),
            Joint(f"{side}_knee", "revolute", f"{side}_hip", f"{side}_knee", (0.0, 0.0, -thigh), (0.0, -1.0, 0.0),
                  -2.5, 0.0),
            Joint(f"{side}_ankle", "revolute", f"{side}_knee", f"{side}_ankle", (0.0, 0.0, -shank),
                  (0.0, -1.0, 0.0), -0.8, 0.8),
        ]
    return Body(height, mass, tuple(links), tuple(joints), hip_height, thigh, shank, ankle, foot_length)


def human_urdf(body: Body, name: str = "human") -> str:
    """The URDF text of ``body`` (robot ``name``): links with ``<inertial>``, ``<visual>`` (with its colour as a
    ``<material>``) and ``<collision>`` per shape (capsules as ``<capsule radius length>``), joints with limits."""
    virtual = sum(1 for link in body.links if link.mass_share == 0.0)
    scale = (body.mass - virtual * _VIRTUAL_MASS) / body.mass
    robot = etree.Element("robot", name=name)
    for link in body.links:
        element = etree.SubElement(robot, "link", name=link.name)
        mass = link.mass_share * body.mass * scale if link.mass_share else _VIRTUAL_MASS
        _inertial(element, mass, link.shapes)
        for number, shape in enumerate(link.shapes):
            for tag in ("visual", "collision"):
                part = etree.SubElement(element, tag)
                etree.SubElement(part, "origin", xyz=_text(shape.xyz), rpy=_text(shape.rpy))
                _geometry(etree.SubElement(part, "geometry"), shape)
                if tag == "visual":
                    material = etree.SubElement(part, "material", name=f"{link.name}_{number}")
                    etree.SubElement(material, "color", rgba=_text(shape.color))
    for joint in body.joints:
        element = etree.SubElement(robot, "joint", name=joint.name, type=joint.type)
        etree.SubElement(element, "parent", link=joint.parent)
        etree.SubElement(element, "child", link=joint.child)
        etree.SubElement(element, "origin", xyz=_text(joint.xyz), rpy="0 0 0")
        if joint.type == "revolute":
            etree.SubElement(element, "axis", xyz=_text(joint.axis))
            etree.SubElement(element, "limit", lower=repr(joint.lower), upper=repr(joint.upper), effort="1000",
                             velocity="10")
    return etree.tostring(robot, encoding="unicode", pretty_print=True)


def _text(values: tuple[float, ...]) -> str:
    return " ".join(repr(round(float(v), 9)) for v in values)


def _geometry(geometry: etree._Element, shape: Shape) -> None:
    if shape.kind == "capsule":
        etree.SubElement(geometry, "capsule", radius=repr(shape.size[0]), length=repr(shape.size[1]))
    elif shape.kind == "sphere":
        etree.SubElement(geometry, "sphere", radius=repr(shape.size[0]))
    else:
        etree.SubElement(geometry, "box", size=_text(shape.size))


def _inertial(link: etree._Element, mass: float, shapes: tuple[Shape, ...]) -> None:
    """Mass at the first shape's centre with the inertia of a solid box of that shape's extent (a person is held
    kinematically: these matter only with dynamics on)."""
    inertial = etree.SubElement(link, "inertial")
    xyz = shapes[0].xyz if shapes else (0.0, 0.0, 0.0)
    etree.SubElement(inertial, "origin", xyz=_text(xyz), rpy="0 0 0")
    etree.SubElement(inertial, "mass", value=repr(mass))
    if shapes:
        sx, sy, sz = _extent(shapes[0])
        ixx, iyy, izz = (mass * (b * b + c * c) / 12 for b, c in ((sy, sz), (sx, sz), (sx, sy)))
    else:
        ixx = iyy = izz = 1e-5
    etree.SubElement(inertial, "inertia", ixx=repr(ixx), iyy=repr(iyy), izz=repr(izz), ixy="0", ixz="0", iyz="0")


def _extent(shape: Shape) -> tuple[float, float, float]:
    """Full lengths of ``shape``'s box in its link frame (a capsule across y when rolled by π/2)."""
    if shape.kind == "box":
        return shape.size[0], shape.size[1], shape.size[2]
    if shape.kind == "sphere":
        d = 2 * shape.size[0]
        return d, d, d
    d, length = 2 * shape.size[0], shape.size[1] + 2 * shape.size[0]
    return (d, length, d) if abs(shape.rpy[0]) > 1.0 else (d, d, length)
