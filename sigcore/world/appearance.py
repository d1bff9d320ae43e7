"""How each entity of a world looks: its visuals and colours in its own frames, made from the world file (primitive
and mesh objects) and the URDFs' ``<visual>`` elements (:mod:`sigcore.world.visuals`; a person's URDF is generated
by :mod:`sigcore.world.body`), with no engine.

The scene description (:class:`sigcore.scene.Scene`) holds these for a running simulation; the footprints
(:mod:`sigcore.world.footprints`) and both backends' builders (the link colours) read them here.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np
from lxml import etree

from ..geometry import quat_mul, quat_rotate, quat_to_matrix
from .models import Entity, Human, Object, Robot, World
from .visuals import Visual, mesh_vertex_bounds, origin, urdf_visuals

_IDENTITY: tuple[float, float, float, float] = (1.0, 0.0, 0.0, 0.0)


@dataclass(frozen=True)
class EntityScene:
    """The visuals of one entity.

    Attributes:
        name: The entity.
        kind: ``robot``, ``object`` or ``human``.
        visuals: Its visuals (an entity whose URDF has no ``<visual>`` has none).
    """

    name: str
    kind: str
    visuals: tuple[Visual, ...]


FrameName = Callable[[str, str], str]
"""``(robot, link) -> TF frame name`` (``Frames.name``)."""


def entity_scene(world: World, entity: Entity, frame: FrameName) -> EntityScene:
    """The visuals of ``entity`` of ``world``; a robot's link frames are named by ``frame``."""
    if isinstance(entity, Robot | Human):  # a person's URDF is generated (sigcore.world.body)
        document = world.urdf(entity.name)
        visuals = tuple(replace(v, frame=frame(entity.name, v.frame))
                        for v in urdf_visuals(document.root, document.path.parent))
        return EntityScene(entity.name, entity.kind, visuals)
    if entity.urdf is not None:
        return EntityScene(entity.name, "object", _urdf_object(world, entity))
    origin_ = (0.0, 0.0, 0.0)
    if entity.mesh is not None:
        mesh = world.resolve(entity.mesh).resolve()
        return EntityScene(entity.name, "object", (Visual(entity.name, "mesh", (entity.scale,) * 3, origin_,
                                                          _IDENTITY, entity.color, mesh),))
    assert entity.shape is not None and entity.size is not None
    return EntityScene(entity.name, "object", (Visual(entity.name, entity.shape, tuple(entity.size), origin_,
                                                      _IDENTITY, entity.color),))


Color = tuple[float, float, float, float]
"""r, g, b, a in [0, 1]."""


def _given_color(entity: Entity) -> Color | None:
    """The world file's ``color`` of a URDF object when the file gives one: it replaces the URDF's colours."""
    return entity.color if isinstance(entity, Object) and "color" in entity.model_fields_set else None


def link_colors(world: World, entity: Entity) -> dict[str, Color]:
    """The colour of each URDF link of a robot, a person or a URDF object of ``world``, as the scene shows it.

    The backends drop the URDFs' ``<visual>`` elements and their cameras render the collision geometry, so they
    paint each link's collision geometry with this colour: the camera, the viewer and ``/sigcore/scene`` then show
    one colour, from this module. It is the world file's ``color`` for an object that gives one, else the colour of
    the link's first ``<visual>``.

    Returns:
        Colour by URDF link name (a person's generated one too); links with no visual are absent (paint them
        :data:`~sigcore.world.visuals.DEFAULT_COLOR`); empty for shapes and meshes.
    """
    if isinstance(entity, Object) and entity.urdf is None:
        return {}
    document = world.urdf(entity.name)
    given = _given_color(entity)
    colors: dict[str, Color] = {}
    for v in urdf_visuals(document.root, document.path.parent):
        colors.setdefault(v.frame, given or v.color)
    return colors


def _urdf_object(world: World, obj: Object) -> tuple[Visual, ...]:
    """A URDF object's visuals in its entity frame (the root link's), joints at zero, scaled by ``obj.scale``;
    the world file's ``color`` replaces the URDF's colours when it is given."""
    document = world.urdf(obj.name)
    links = links_in_root(document.root, document.model.root)
    s = obj.scale
    color = _given_color(obj)
    out = []
    for v in urdf_visuals(document.root, document.path.parent):
        pos, quat = links[v.frame]
        xyz = pos + quat_rotate(quat, np.array(v.xyz))
        wxyz = quat_mul(quat, np.array(v.wxyz))
        size = tuple(x * s for x in v.size)
        out.append(Visual(obj.name, v.shape, size, (float(xyz[0] * s), float(xyz[1] * s), float(xyz[2] * s)),
                          (float(wxyz[0]), float(wxyz[1]), float(wxyz[2]), float(wxyz[3])),
                          color or v.color, v.mesh))
    return tuple(out)


def links_in_root(root: etree._Element, root_link: str) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Pose ``(xyz, wxyz)`` of every link in the root link's frame, every joint at its zero position."""
    joints = {}
    for joint in root.findall("joint"):
        parent, child = joint.find("parent"), joint.find("child")
        if parent is not None and child is not None:
            joints[str(child.get("link"))] = (str(parent.get("link")), origin(joint.find("origin")))
    poses: dict[str, tuple[np.ndarray, np.ndarray]] = {root_link: (np.zeros(3), np.array(_IDENTITY))}

    def pose(link: str) -> tuple[np.ndarray, np.ndarray]:
        if link not in poses:  # the names model checked that the joints form one tree
            parent, (xyz, wxyz) = joints[link]
            pp, pq = pose(parent)
            poses[link] = (pp + quat_rotate(pq, np.array(xyz)), quat_mul(pq, np.array(wxyz)))
        return poses[link]

    for link in root.findall("link"):
        pose(str(link.get("name")))
    return poses


def _local_box(visual: Visual) -> tuple[np.ndarray, np.ndarray] | None:
    """``(min, max)`` of ``visual``'s geometry in its own frame [m]; None for a mesh whose vertices cannot be
    read."""
    s = visual.size
    if visual.shape == "box":
        half = np.array(s) / 2
    elif visual.shape == "sphere":
        half = np.full(3, s[0])
    elif visual.shape == "cylinder":
        half = np.array([s[0], s[0], s[1] / 2])
    elif visual.shape == "capsule":
        half = np.array([s[0], s[0], s[1] / 2 + s[0]])
    else:
        assert visual.mesh is not None
        box = mesh_vertex_bounds(visual.mesh)
        if box is None:
            return None
        a, b = np.array(box[0]) * np.array(s), np.array(box[1]) * np.array(s)
        return np.minimum(a, b), np.maximum(a, b)
    return -half, half


_CORNERS = np.array([[(i >> k) & 1 for k in range(3)] for i in range(8)], dtype=float)


def visual_corners(visual: Visual, pos: np.ndarray, quat: np.ndarray) -> np.ndarray | None:
    """The 8 corners (8, 3) [m] of ``visual``'s box in the frame where its own frame has pose ``(pos, quat)``;
    None for a mesh whose vertices cannot be read."""
    box = _local_box(visual)
    if box is None:
        return None
    lo, hi = box
    rotation = quat_to_matrix(quat_mul(quat, np.array(visual.wxyz)))
    offset = pos + quat_rotate(quat, np.array(visual.xyz))
    return (lo + _CORNERS * (hi - lo)) @ rotation.T + offset
