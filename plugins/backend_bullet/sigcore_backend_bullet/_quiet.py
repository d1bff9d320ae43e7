"""Import ``pybullet`` without its banner.

PyBullet 3.2.7's C module writes ``pybullet build time: ...`` to the process's standard error when it is
imported. Every ``sigcore`` command loads the installed plugins, so without this every command (``sigcore
plugins``, ``sigcore api``, a run) would print it. :func:`import_pybullet` imports the module with file
descriptor 2 pointed at ``/dev/null``; an import error still raises normally.
"""

from __future__ import annotations

import os
import sys


def import_pybullet() -> None:
    """Import ``pybullet`` once with standard error silenced at the file-descriptor level."""
    if "pybullet" in sys.modules:
        return
    sys.stderr.flush()
    saved = os.dup(2)
    devnull = os.open(os.devnull, os.O_WRONLY)
    try:
        os.dup2(devnull, 2)
        import pybullet  # noqa: F401
    finally:
        os.dup2(saved, 2)
        os.close(saved)
        os.close(devnull)
