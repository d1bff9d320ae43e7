"""The read side of simulation_interfaces: entity filters, entity information and bounds, named poses.

What an entity is (category, description, tags) is the core's ``sim.entities.info``; its axis-aligned box in
``world`` is the
core's scene description, ``sim.scene.bounds``; named poses are the world file's ``<named_pose>`` elements and each
robot's ``<robot>_start`` (``World.all_named_poses``). This module only translates. Bounds are returned as TYPE_BOX
with ``points[0]`` the minimum and ``points[1]`` the maximum corner; a filter box may give its two corners in either
order.
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np
from geometry_msgs.msg import Vector3
from simulation_interfaces.msg import Bounds, EntityCategory, EntityInfo, NamedPose, Result, TagsFilter

from sigcore.agent.exceptions import ApiError
from sigcore.geometry import quat_from_rpy
from sigcore.sim.info import Category, named_poses_with_tags
from sigcore.text import clip, quote

from .exceptions import Refusal

if TYPE_CHECKING:
    from sigcore.sim.simulation import Simulation

    Box = tuple[np.ndarray, np.ndarray]

CATEGORY_CODES: dict[Category, int] = {
    "object": EntityCategory.CATEGORY_OBJECT, "robot": EntityCategory.CATEGORY_ROBOT,
    "human": EntityCategory.CATEGORY_HUMAN, "dynamic_object": EntityCategory.CATEGORY_DYNAMIC_OBJECT,
    "static_object": EntityCategory.CATEGORY_STATIC_OBJECT,
}
"""The core's category names as EntityCategory constants."""

CATEGORY_NAMES: dict[int, Category] = {code: name for name, code in CATEGORY_CODES.items()}
_VALID_CATEGORIES = ", ".join(f"{code} CATEGORY_{name.upper()}" for name, code in CATEGORY_CODES.items())
_VALID_BOUNDS = "0 TYPE_EMPTY, 1 TYPE_BOX (2 corners), 3 TYPE_SPHERE (centre, radius in x)"


def _ok() -> Result:
    return Result(result=Result.RESULT_OK, error_message="")


def _point(v: Any) -> tuple[float, float, float]:
    return (float(v.x), float(v.y), float(v.z))


def bounds_test(bounds: Any) -> Callable[[Box], bool] | None:
    """Whether an entity's box overlaps the filter ``bounds`` (touching counts); None for TYPE_EMPTY.

    Raises:
        Refusal: an unknown type, TYPE_CONVEX_HULL (FEATURE_UNSUPPORTED), a wrong number of points, a point that is
            not finite, a negative radius (OPERATION_FAILED, naming the valid values).
    """
    kind, points = int(bounds.type), [_point(p) for p in bounds.points]
    failed = Result.RESULT_OPERATION_FAILED
    if kind == Bounds.TYPE_EMPTY:
        if points:
            raise Refusal(failed, f"bounds TYPE_EMPTY with {len(points)} points; valid: no points (no filter)")
        return None
    if kind == Bounds.TYPE_CONVEX_HULL:
        raise Refusal(Result.RESULT_FEATURE_UNSUPPORTED, "TYPE_CONVEX_HULL bounds are not supported; valid: "
                                                         "TYPE_BOX or TYPE_SPHERE")
    if kind not in (Bounds.TYPE_BOX, Bounds.TYPE_SPHERE):
        raise Refusal(failed, f"bounds type {kind} is unknown; valid: {_VALID_BOUNDS}")
    name = "TYPE_BOX" if kind == Bounds.TYPE_BOX else "TYPE_SPHERE"
    if len(points) != 2:
        raise Refusal(failed, f"{name} bounds with {len(points)} points; valid: exactly 2 ({_VALID_BOUNDS})")
    if not all(math.isfinite(c) for p in points for c in p):
        raise Refusal(failed, f"{name} bounds points must be finite numbers [m], got {points}")
    a, b = np.array(points[0]), np.array(points[1])
    if kind == Bounds.TYPE_BOX:
        lo, hi = np.minimum(a, b), np.maximum(a, b)
        return lambda box: bool(np.all(box[0] <= hi) and np.all(lo <= box[1]))
    radius = float(b[0])
    if radius < 0:
        raise Refusal(failed, f"TYPE_SPHERE radius (points[1].x) is {radius:g}; valid: >= 0 [m]")
    return lambda box: float(np.linalg.norm(np.clip(a, box[0], box[1]) - a)) <= radius


def tags_of(tags: Any) -> tuple[set[str], bool]:
    """The wanted tags of a TagsFilter and whether all must match.

    Raises:
        Refusal: a filter mode other than ANY (0) or ALL (1).
    """
    mode = int(tags.filter_mode)
    if mode not in (TagsFilter.FILTER_MODE_ANY, TagsFilter.FILTER_MODE_ALL):
        raise Refusal(Result.RESULT_OPERATION_FAILED,
                      f"tags filter_mode {mode} is unknown; valid: 0 FILTER_MODE_ANY, 1 FILTER_MODE_ALL")
    return set(tags.tags), mode == TagsFilter.FILTER_MODE_ALL


class EntityQueries:
    """Entity filters, entity information and bounds, named poses (run on the simulation thread).

    Args:
        sim: The simulation.
    """

    def __init__(self, sim: Simulation) -> None:
        self.sim = sim

    # ------------------------------------------------------------------ filters
    def select(self, filters: Any) -> list[str]:
        """The entities that pass every filter of an EntityFilters, in the world file's order.

        Raises:
            Refusal: a bad regular expression, category, tags mode or bounds (see :func:`bounds_test`).
        """
        info = self.sim.entities.info
        names = info.names
        if filters.filter:
            try:
                pattern = re.compile(filters.filter)
            except re.error as e:
                raise Refusal(Result.RESULT_OPERATION_FAILED, f"filter {quote(filters.filter)} is not a regular "
                                                              f"expression: {e}") from None
            names = [n for n in names if pattern.search(n)]
        if len(filters.categories):
            codes = [int(c.category) for c in filters.categories]
            unknown = [c for c in codes if c not in CATEGORY_NAMES]
            if unknown:
                raise Refusal(Result.RESULT_OPERATION_FAILED,
                              f"category {unknown[0]} is unknown; valid: {_VALID_CATEGORIES}")
            allowed = set(info.in_categories(CATEGORY_NAMES[c] for c in codes))
            names = [n for n in names if n in allowed]
        tags, match_all = tags_of(filters.tags)
        if tags:
            tagged = set(info.with_tags(tags, match_all))
            names = [n for n in names if n in tagged]
        overlaps = bounds_test(filters.bounds)
        if overlaps is not None:
            names = [n for n in names if overlaps(self.sim.scene.bounds(n))]
        return names

    def _known(self, entity: str) -> None:
        if entity not in self.sim.entities.info.names:
            raise Refusal(Result.RESULT_NOT_FOUND,
                          f"no entity {quote(entity)}; entities: {', '.join(self.sim.entities.info.names)}")

    # ------------------------------------------------------------------ services: (request, response, reply)
    # Each fills ``response`` and returns False (answered at once), like SimInterfaces' own.
    def get_entity_info(self, req: Any, res: Any, reply: Any) -> bool:
        """GetEntityInfo: category, description and tags of an entity now."""
        self._known(req.entity)
        info = self.sim.entities.info.get(req.entity)
        res.info = EntityInfo(category=EntityCategory(category=CATEGORY_CODES[info.category]),
                              description=info.description, tags=list(info.tags))
        res.result = _ok()
        return False

    def set_entity_info(self, req: Any, res: Any, reply: Any) -> bool:
        """SetEntityInfo: replace an entity's category, description and tags (all three)."""
        self._known(req.entity)
        code = int(req.info.category.category)
        if code not in CATEGORY_NAMES:
            raise Refusal(Result.RESULT_OPERATION_FAILED, f"category {code} is unknown; valid: {_VALID_CATEGORIES}")
        try:
            self.sim.inputs.entity_info(req.entity, CATEGORY_NAMES[code], req.info.description, list(req.info.tags),
                                        what=f"set_entity_info {req.entity}")
        except ApiError as e:
            raise Refusal(Result.RESULT_OPERATION_FAILED, f"entity {quote(req.entity)}: {clip(str(e), 300)}") from None
        res.result = _ok()
        return False

    def get_entity_bounds(self, req: Any, res: Any, reply: Any) -> bool:
        """GetEntityBounds: the entity's axis-aligned box in ``world`` at its current pose (TYPE_BOX)."""
        self._known(req.entity)
        lo, hi = self.sim.scene.bounds(req.entity)
        res.bounds = bounds_box(lo, hi)
        res.result = _ok()
        return False

    def get_named_poses(self, req: Any, res: Any, reply: Any) -> bool:
        """GetNamedPoses: the named poses whose tags pass the filter."""
        tags, match_all = tags_of(req.tags)
        res.poses = [_named_pose(p) for p in named_poses_with_tags(self.sim.world.all_named_poses(), tags,
                                                                   match_all)]
        res.result = _ok()
        return False

    def get_named_pose_bounds(self, req: Any, res: Any, reply: Any) -> bool:
        """GetNamedPoseBounds: the pose's box in ``world`` (TYPE_BOX), TYPE_EMPTY (unbounded) when it has none."""
        poses = {p.name: p for p in self.sim.world.all_named_poses()}
        pose = poses.get(req.name)
        if pose is None:
            raise Refusal(Result.RESULT_NOT_FOUND,
                          f"no named pose {quote(req.name)}; named poses: {', '.join(poses) or 'none'}")
        if pose.bounds is None:
            res.bounds = Bounds(type=Bounds.TYPE_EMPTY)
        else:
            at, b = np.array(pose.pose.xyz), pose.bounds
            res.bounds = bounds_box(at + np.array(b[:3]), at + np.array(b[3:]))
        res.result = _ok()
        return False


def bounds_box(lo: Any, hi: Any) -> Bounds:
    """A TYPE_BOX Bounds with corners ``lo`` (minimum) and ``hi`` (maximum) [m]."""
    return Bounds(type=Bounds.TYPE_BOX, points=[Vector3(x=float(lo[0]), y=float(lo[1]), z=float(lo[2])),
                                                Vector3(x=float(hi[0]), y=float(hi[1]), z=float(hi[2]))])


def _named_pose(pose: Any) -> NamedPose:
    out = NamedPose(name=pose.name, description=pose.description, tags=list(pose.tags))
    p, o = out.pose.position, out.pose.orientation
    p.x, p.y, p.z = (float(v) for v in pose.pose.xyz)
    o.w, o.x, o.y, o.z = (float(v) for v in quat_from_rpy(*pose.pose.rpy))
    return out
