"""The scene description's visuals (:class:`sigcore.world.visuals.Visual`) as viser scene nodes."""

from __future__ import annotations

import logging
from functools import lru_cache
from pathlib import Path
from typing import Any

import numpy as np

from sigcore.geometry import quat_mul, quat_rotate
from sigcore.world.visuals import Visual

log = logging.getLogger("sigcore.viewer")

# viser's cylinder lies along its local y axis; the scene's cylinders and capsules lie along z
_Y_TO_Z = np.array([np.cos(np.pi / 4), np.sin(np.pi / 4), 0.0, 0.0])


def rgb(color: tuple[float, ...]) -> tuple[int, int, int]:
    """``(r, g, b)`` in 0..255 of a colour in [0, 1]."""
    return tuple(int(round(max(0.0, min(1.0, c)) * 255)) for c in color[:3])  # type: ignore[return-value]


def add_visual(scene: Any, name: str, visual: Visual) -> list[Any]:
    """Add ``visual`` as node(s) called ``name`` (a child of its frame's node) to the viser ``scene``; the
    handles (empty for a mesh that cannot be read, which is logged)."""
    color = rgb(visual.color)
    opacity = visual.color[3] if len(visual.color) > 3 and visual.color[3] < 1.0 else None
    xyz = np.array(visual.xyz, dtype=float)
    wxyz = np.array(visual.wxyz, dtype=float)
    s = visual.size
    if visual.shape == "box":
        return [scene.add_box(name, color=color, dimensions=tuple(s), position=xyz, wxyz=wxyz, opacity=opacity)]
    if visual.shape == "sphere":
        return [scene.add_icosphere(name, radius=s[0], color=color, subdivisions=2, position=xyz, wxyz=wxyz,
                                    opacity=opacity)]
    if visual.shape in ("cylinder", "capsule"):
        radius, length = s[0], s[1]
        along_z = quat_mul(wxyz, _Y_TO_Z)
        out = [scene.add_cylinder(name, radius=radius, height=length, color=color, radial_segments=20,
                                  position=xyz, wxyz=along_z, opacity=opacity)]
        if visual.shape == "capsule":  # the two half-sphere ends
            axis = quat_rotate(wxyz, np.array([0.0, 0.0, 1.0]))
            for k, sign in ((0, 1.0), (1, -1.0)):
                out.append(scene.add_icosphere(f"{name}_end{k}", radius=radius, color=color, subdivisions=2,
                                               position=xyz + sign * axis * length / 2, opacity=opacity))
        return out
    if visual.shape == "mesh" and visual.mesh is not None:
        mesh = _read_mesh(visual.mesh)
        if mesh is None:
            return []
        vertices, faces = mesh
        return [scene.add_mesh_simple(name, vertices * np.array(s), faces, color=color, position=xyz, wxyz=wxyz,
                                      opacity=opacity)]
    log.warning("viewer: visual of shape %r is not drawn", visual.shape)
    return []


@lru_cache(maxsize=64)
def _read_mesh(path: Path) -> tuple[np.ndarray, np.ndarray] | None:
    """``(vertices (n, 3), faces (m, 3))`` of a mesh file through trimesh (viser's own dependency); None, logged,
    when it cannot be read."""
    try:
        import trimesh

        loaded: Any = trimesh.load(str(path), force="mesh")
        vertices = np.asarray(loaded.vertices, dtype=np.float32)
        faces = np.asarray(loaded.faces, dtype=np.uint32)
    except Exception as e:  # any reader failure: the mesh is left out, the viewer goes on
        log.warning("viewer: mesh %s cannot be read (%s: %s); it is not drawn", path, type(e).__name__, e)
        return None
    if len(vertices) == 0 or len(faces) == 0:
        log.warning("viewer: mesh %s has no triangles; it is not drawn", path)
        return None
    return vertices, faces
