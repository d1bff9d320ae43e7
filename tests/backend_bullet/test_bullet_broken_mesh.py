"""A mesh that breaks after the world was read (or a World built in Python) never reaches PyBullet, which would
crash the whole process on it: the backend refuses it with a BackendError naming the object."""

from __future__ import annotations

import struct
import subprocess
import sys
import textwrap
from pathlib import Path

WORLD = """<world name="m" timestep="0.002">
  <object name="part" mesh="part.stl" pose="0 0 0.5 0 0 0"/>
</world>
"""


def _stl(triangles: int, declared: int) -> bytes:
    tri = struct.pack("<12fH", *([0.0] * 3 + [0, 0, 0, 0.1, 0, 0, 0, 0.1, 0]), 0)
    return b"\0" * 80 + struct.pack("<I", declared) + tri * triangles


def test_a_mesh_broken_after_parsing_is_refused_not_a_crash(tmp_path: Path) -> None:
    """The world is read with a good binary STL, then the file is replaced by one that declares 100,000 triangles
    and holds one (PyBullet segfaults on it): building on PyBullet raises BackendError naming 'part', the process
    lives (run in a subprocess so that a crash would show as its exit code)."""
    (tmp_path / "w.xml").write_text(WORLD)
    (tmp_path / "part.stl").write_bytes(_stl(1, 1))
    script = textwrap.dedent(f"""
        from pathlib import Path
        from sigcore.backend import BackendError
        from sigcore.world import parse_world
        from sigcore_backend_bullet.backend import BulletBackend
        world = parse_world(Path({str(tmp_path / "w.xml")!r}))
        Path({str(tmp_path / "part.stl")!r}).write_bytes(bytes.fromhex({_stl(1, 100_000).hex()!r}))
        try:
            BulletBackend().build(world)
        except BackendError as e:
            print("refused:", e)
    """)
    proc = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert "refused: object 'part'" in proc.stdout and "triangle" in proc.stdout, proc.stdout
