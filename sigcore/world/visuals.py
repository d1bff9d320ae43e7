"""The ``<visual>`` elements of a parsed URDF: geometry, pose in its link and colour, for viewers and bounds.

Read from a shared :attr:`sigcore.world.urdf.UrdfDocument.root` (never changed here). Meshes are resolved to
absolute files with :func:`sigcore.world.urdf.resolve_mesh`; a mesh that cannot be resolved is left out with a
warning (the world parser already refused broken ones that exist). :func:`mesh_vertex_bounds` reads the vertex
box of an ``.obj`` or ``.stl`` file without any mesh library.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np
from lxml import etree

from ..geometry import quat_from_rpy
from .limits import parse_floats
from .urdf import resolve_mesh

log = logging.getLogger("sigcore")

DEFAULT_COLOR: tuple[float, float, float, float] = (0.7, 0.7, 0.7, 1.0)
"""A visual without a colour (no material, or a material with a texture only): a neutral grey, opaque."""


@dataclass(frozen=True)
class Visual:
    """One piece of visual geometry: a URDF ``<visual>`` (in its link's frame) or, in the scene description
    (:mod:`sigcore.scene`), any entity's visual in a TF frame.

    Attributes:
        frame: The frame it is attached to: the link's name for a URDF visual read here; the TF frame in the scene
            (a robot's link frame, or the entity's frame).
        shape: ``box``, ``sphere``, ``cylinder``, ``capsule`` (a world primitive, or a URDF ``<capsule>`` as
            MuJoCo and PyBullet read it) or ``mesh``; cylinders and capsules along z.
        size: box: full lengths (3,) [m]; sphere: (radius,) [m]; cylinder, capsule: (radius, length) [m] (a
            capsule's length is its cylindrical part's); mesh: scale per axis (3,).
        xyz: Position in ``frame`` [m] (``<origin xyz>``).
        wxyz: Orientation in ``frame``, unit quaternion (w, x, y, z) (``<origin rpy>``).
        color: r, g, b, a in [0, 1].
        mesh: The absolute mesh file (shape ``mesh`` only).
    """

    frame: str
    shape: str
    size: tuple[float, ...]
    xyz: tuple[float, float, float]
    wxyz: tuple[float, float, float, float]
    color: tuple[float, float, float, float]
    mesh: Path | None = None


def urdf_visuals(root: etree._Element, urdf_dir: Path) -> list[Visual]:
    """Every ``<visual>`` of every link of the parsed URDF ``root``, in file order.

    Args:
        root: The ``<robot>`` element (read only).
        urdf_dir: The URDF file's directory (relative and ``package://`` meshes are resolved from it).

    Returns:
        The visuals; a visual without a known geometry, or whose mesh cannot be resolved, is left out (logged).
    """
    materials = _materials(root)
    out: list[Visual] = []
    for link in root.findall("link"):
        name = str(link.get("name"))
        for visual in link.findall("visual"):
            geometry = _geometry(visual, name, urdf_dir)
            if geometry is None:
                continue
            shape, size, mesh = geometry
            xyz, wxyz = origin(visual.find("origin"))
            out.append(Visual(name, shape, size, xyz, wxyz, _color(visual.find("material"), materials), mesh))
    return out


def origin(element: etree._Element | None) -> tuple[tuple[float, float, float], tuple[float, float, float, float]]:
    """``(xyz [m], (w, x, y, z))`` of an ``<origin xyz rpy>`` element (identity when absent or unreadable: the
    parser checked the numbers of links' origins)."""
    if element is None:
        return (0.0, 0.0, 0.0), (1.0, 0.0, 0.0, 0.0)
    xyz = _floats(element.get("xyz"), 3) or (0.0, 0.0, 0.0)
    rpy = _floats(element.get("rpy"), 3) or (0.0, 0.0, 0.0)
    q = quat_from_rpy(*rpy)
    return (xyz[0], xyz[1], xyz[2]), (float(q[0]), float(q[1]), float(q[2]), float(q[3]))


def _floats(text: str | None, count: int) -> tuple[float, ...] | None:
    if text is None:
        return None
    try:
        return parse_floats(text, count)
    except ValueError:
        return None


def _geometry(visual: etree._Element, link: str,
              urdf_dir: Path) -> tuple[str, tuple[float, ...], Path | None] | None:
    """``(shape, size, mesh file)`` of a visual's ``<geometry>``; None (logged) if it has none that is known."""
    geometry = visual.find("geometry")
    shape = next(iter(geometry), None) if geometry is not None else None
    while shape is not None and not isinstance(shape.tag, str):  # comments
        shape = shape.getnext()
    tag = shape.tag if shape is not None else None
    size: tuple[float, ...] | None = None
    mesh: Path | None = None
    if shape is not None and tag == "box":
        size = _floats(shape.get("size"), 3)
    elif shape is not None and tag == "sphere":
        size = _floats(shape.get("radius"), 1)
    elif shape is not None and tag in ("cylinder", "capsule"):  # <capsule>: the engines' URDF extension
        radius, length = _floats(shape.get("radius"), 1), _floats(shape.get("length"), 1)
        size = (radius[0], length[0]) if radius and length else None
    elif shape is not None and tag == "mesh":
        filename = str(shape.get("filename", ""))
        mesh = resolve_mesh(filename, urdf_dir)
        if mesh is None:
            log.warning("link '%s': visual mesh %r not found from %s; left out of the scene", link, filename,
                        urdf_dir)
            return None
        scale = shape.get("scale")
        size = _floats(scale, 3) if scale is not None else (1.0, 1.0, 1.0)
    if size is None or tag is None:
        log.warning("link '%s': a <visual> without a readable box, sphere, cylinder or mesh (line %s); left out "
                    "of the scene", link, visual.sourceline)
        return None
    return str(tag), size, mesh


def _rgba(material: etree._Element) -> tuple[float, float, float, float] | None:
    color = material.find("color")
    values = _floats(color.get("rgba"), 4) if color is not None else None
    if values is None:
        return None
    r, g, b, a = (min(1.0, max(0.0, v)) for v in values)
    return r, g, b, a


def _materials(root: etree._Element) -> dict[str, tuple[float, float, float, float]]:
    """The colours of the materials defined at robot level, and of named materials defined inline in a visual
    (URDF readers accept a name defined once and referred to elsewhere)."""
    named: dict[str, tuple[float, float, float, float]] = {}
    for material in [*root.findall("link/visual/material"), *root.findall("material")]:
        rgba = _rgba(material)
        if rgba is not None and material.get("name"):
            named[str(material.get("name"))] = rgba
    return named


def _color(material: etree._Element | None,
           named: dict[str, tuple[float, float, float, float]]) -> tuple[float, float, float, float]:
    if material is None:
        return DEFAULT_COLOR
    return _rgba(material) or named.get(str(material.get("name", "")), DEFAULT_COLOR)


@lru_cache(maxsize=256)
def mesh_vertex_bounds(path: Path) -> tuple[tuple[float, float, float], tuple[float, float, float]] | None:
    """``(min xyz, max xyz)`` [file units] of the vertices of the ``.obj`` or ``.stl`` file ``path``; None for
    another format or a file that cannot be read (read once per path)."""
    try:
        suffix = path.suffix.lower()
        if suffix == ".obj":
            points = _obj_vertices(path)
        elif suffix == ".stl":
            points = _stl_vertices(path)
        else:
            return None
    except (OSError, ValueError):
        return None
    if points.size == 0 or not np.all(np.isfinite(points)):
        return None
    lo, hi = points.min(axis=0), points.max(axis=0)
    return (float(lo[0]), float(lo[1]), float(lo[2])), (float(hi[0]), float(hi[1]), float(hi[2]))


def _obj_vertices(path: Path) -> np.ndarray:
    rows = [line.split()[1:4] for line in path.read_bytes().splitlines() if line.startswith(b"v ")]
    return np.array(rows, dtype=float).reshape(-1, 3)


def _stl_vertices(path: Path) -> np.ndarray:
    data = path.read_bytes()
    count = int.from_bytes(data[80:84], "little") if len(data) >= 84 else -1
    if count > 0 and 84 + 50 * count == len(data):  # binary (even if its header says "solid")
        record = np.dtype([("normal", "<f4", 3), ("v", "<f4", (3, 3)), ("attr", "<u2")])
        return np.frombuffer(data, record, count, 84)["v"].reshape(-1, 3).astype(float)
    rows = [line.split()[1:4] for line in data.splitlines() if line.strip().startswith(b"vertex")]
    return np.array(rows, dtype=float).reshape(-1, 3)
