"""A cheap sanity check of mesh files when a world is read, before an engine decodes them.

Engines handle broken meshes badly: PyBullet crashes the whole process (a segmentation fault) on a binary STL whose
size does not match its triangle count, and accepts an OBJ with ``nan`` vertices. :func:`mesh_problem` finds what
can be found without decoding the mesh: an empty file, a binary STL of the wrong size, an OBJ vertex that is not
three finite numbers or a face naming no vertex. What passes may still be refused by the engine, which
then names the entity.
"""

from __future__ import annotations

import math
from pathlib import Path

MESH_SUFFIXES = (".stl", ".obj")
"""The mesh formats sigcore's backends read (MuJoCo also reads .msh, which is not checked here)."""


def mesh_problem(path: Path) -> str | None:
    """What is wrong with the mesh file at ``path``, or None if nothing was found (or the format is not checked).

    Args:
        path: An existing file.
    """
    try:
        size = path.stat().st_size
        if size == 0:
            return "the file is empty"
        suffix = path.suffix.lower()
        if suffix == ".stl":
            return _stl(path, size)
        if suffix == ".obj":
            return _obj(path)
    except OSError as e:
        return f"cannot read it: {e.strerror}"
    return None


def _stl(path: Path, size: int) -> str | None:
    with path.open("rb") as f:
        head = f.read(84)
    if head.lstrip().startswith(b"solid"):  # ASCII, or a binary one whose header says "solid"
        if size >= 84 and 84 + 50 * int.from_bytes(head[80:84], "little") == size:
            return None
        text = path.read_bytes()
        if b"facet" not in text or b"endsolid" not in text:
            return "an ASCII STL without 'facet' ... 'endsolid' (truncated?)"
        return None
    if size < 84:
        return f"a binary STL needs at least 84 bytes, this one has {size} (truncated?)"
    count = int.from_bytes(head[80:84], "little")
    if count == 0 or 84 + 50 * count != size:
        return (f"a binary STL with {count} triangles has {84 + 50 * count} bytes, this one has {size} "
                "(truncated, or not an STL)")
    return None


def _obj(path: Path) -> str | None:
    vertices = 0
    faces = 0
    with path.open("rb") as f:
        for number, raw in enumerate(f, start=1):
            parts = raw.split()
            if not parts:
                continue
            if parts[0] == b"v":
                try:
                    values = [float(p) for p in parts[1:4]]
                except ValueError:
                    return f"line {number}: vertex {raw[:40]!r} is not numbers"
                if len(values) < 3 or not all(math.isfinite(v) for v in values):
                    return f"line {number}: a vertex needs 3 finite numbers, got {raw.strip()[:40]!r}"
                vertices += 1
            elif parts[0] == b"f":
                faces += 1
                for p in parts[1:]:
                    try:
                        index = int(p.split(b"/")[0])
                    except ValueError:
                        return f"line {number}: face {raw.strip()[:40]!r} is not vertex indices"
                    if index == 0 or abs(index) > vertices:
                        return f"line {number}: face names vertex {index}, the file has {vertices} so far"
    if vertices < 4 or faces == 0:
        return f"{vertices} vertices and {faces} faces; a mesh needs at least 4 vertices and a face"
    return None
