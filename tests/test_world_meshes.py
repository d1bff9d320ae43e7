"""The core's mesh sanity check (sigcore.world.meshes): valid meshes pass, broken ones are named."""

from __future__ import annotations

import struct
from pathlib import Path

import pytest

from sigcore.world.meshes import mesh_problem

DATA = Path(__file__).parent / "data"


def _binary_stl(header: bytes, triangles: int) -> bytes:
    facet = struct.pack("<12fH", *([0.0] * 3), 0, 0, 0, 1, 0, 0, 0, 1, 0, 0)
    return header.ljust(80, b" ") + struct.pack("<I", triangles) + facet * triangles


@pytest.mark.parametrize("name, data", [
    ("binary.stl", _binary_stl(b"made by a tool", 3)),
    ("binary_solid_header.stl", _binary_stl(b"solid but binary", 2)),
    ("ascii.stl", b"solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\n"
                  b"endfacet\nendsolid t\n"),
    ("quad.obj", b"# comment\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nvn 0 0 1\nf 1//1 2//1 3//1\nf -1 -2 -3\n"),
])
def test_valid_meshes_pass(tmp_path: Path, name: str, data: bytes) -> None:
    """Binary STL (also with a 'solid' header), ASCII STL and OBJ (normals, negative indices) pass."""
    (tmp_path / name).write_bytes(data)
    assert mesh_problem(tmp_path / name) is None


def test_shipped_test_mesh_passes() -> None:
    """The test data's mug.obj passes."""
    assert mesh_problem(DATA / "worlds" / "models" / "mug.obj") is None


@pytest.mark.parametrize("name, data, words", [
    ("empty.stl", b"", "empty"),
    ("short.stl", _binary_stl(b"x", 3)[:-10], "has 234 bytes, this one has 224"),
    ("nan.obj", b"v nan 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\n", "3 finite numbers"),
    ("index.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 9\n", "names vertex 9"),
])
def test_broken_meshes_are_named(tmp_path: Path, name: str, data: bytes, words: str) -> None:
    """An empty file, a truncated binary STL, a non-finite vertex, a face past the vertices are each named."""
    (tmp_path / name).write_bytes(data)
    problem = mesh_problem(tmp_path / name)
    assert problem is not None and words in problem
