"""Many steps in one call: sigcore's stepping loop compiled in C (``_steps.c``), for runs where Python has nothing
to do between steps.

A step through Python costs about 5 µs more than ``mj_step`` alone (the held entities' write-back, the contact
comparison, the calls). When the core knows that nothing is due for the next ``k`` steps (no lidar scan, no camera
image, no controller action, no ``step`` subscriber, no queued force or message), it asks the backend for ``k``
steps at once, and the compiled loop takes them without coming back to Python. It stops early after a step whose
contacts differ from the previous step's, so that contact events still start at the step they start.

Each step is what :meth:`MujocoBackend.step` does, bit for bit: ``mj_step``, then the held entities' ``qpos``
written back and their velocities zeroed (``tests/backends/test_compiled_steps.py`` compares the two loops).

The loop is compiled once per MuJoCo version and source, with the C compiler found (``cc``, ``gcc``, ``clang`` or
``$CC``) against the headers the ``mujoco`` wheel ships, into ``$XDG_CACHE_HOME/sigcore`` (``~/.cache/sigcore``);
``scripts/setup.sh`` builds it. It calls ``mj_step`` through the address of the library the bindings loaded, so it
links against nothing. Without a compiler, or with ``SIGCORE_COMPILED_STEPS=0``, the backend steps one at a time
in Python (the same results, about 10 % slower); :func:`status` says which and why.
"""

from __future__ import annotations

import ctypes
import hashlib
import logging
import os
import shutil
import subprocess
import tempfile
from functools import cache
from pathlib import Path

import mujoco
import numpy as np

log = logging.getLogger(__name__)

ENV = "SIGCORE_COMPILED_STEPS"
"""Set to ``0`` to step in Python only (a comparison, a machine whose compiled loop misbehaves)."""

SOURCE = Path(__file__).with_name("_steps.c")
FLAGS = ("-O2", "-shared", "-fPIC", "-fexceptions", "-std=c99")

_INT64P = ctypes.POINTER(ctypes.c_longlong)
_DOUBLEP = ctypes.POINTER(ctypes.c_double)


class CompiledSteps:
    """The loaded loop: :meth:`run` takes up to ``n`` steps of ``model``/``data``."""

    def __init__(self, library: ctypes.CDLL, mj_step: int) -> None:
        fn = library.sigcore_steps
        fn.restype = ctypes.c_int
        fn.argtypes = [ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p, ctypes.c_int, _INT64P, _DOUBLEP,
                       ctypes.c_int, _INT64P, ctypes.c_int, ctypes.c_int]
        self._fn = fn
        self._mj_step = ctypes.c_void_p(mj_step)

    def run(self, model: mujoco.MjModel, data: mujoco.MjData, n: int, held: HeldArrays, track_contacts: bool) -> int:
        """Take up to ``n`` steps (at least 1); returns how many were taken.

        Args:
            held: The held entities' qpos addresses and values and dof addresses (:class:`HeldArrays`).
            track_contacts: Stop after the first step whose contacts differ from those before the call.

        Raises:
            MemoryError: no memory for a copy of the contacts (no step was taken).
        """
        taken = int(self._fn(self._mj_step, model._address, data._address, n, held.qpos_ptr, held.values_ptr,
                             held.nqpos, held.dofs_ptr, held.ndofs, 1 if track_contacts else 0))
        if taken < 0:
            raise MemoryError("no memory for a copy of the contacts in the compiled stepping loop")
        return taken


class HeldArrays:
    """The held entities' arrays as the compiled loop reads them (contiguous ``int64``/``float64``, kept alive)."""

    __slots__ = ("key", "_keep", "qpos_ptr", "values_ptr", "dofs_ptr", "nqpos", "ndofs")

    def __init__(self, qpos: np.ndarray, values: np.ndarray, dofs: np.ndarray) -> None:
        self.key = (id(qpos), id(values), id(dofs))
        q = np.ascontiguousarray(qpos, dtype=np.int64)
        v = np.ascontiguousarray(values, dtype=np.float64)
        d = np.ascontiguousarray(dofs, dtype=np.int64)
        self._keep = (qpos, values, dofs, q, v, d)  # the ids in ``key`` stay those of these arrays
        self.qpos_ptr = q.ctypes.data_as(_INT64P)
        self.values_ptr = v.ctypes.data_as(_DOUBLEP)
        self.dofs_ptr = d.ctypes.data_as(_INT64P)
        self.nqpos, self.ndofs = int(q.size), int(d.size)


def status() -> str:
    """One line: whether the compiled loop is used, where it is, or why not."""
    loop = compiled()
    return f"compiled stepping loop: {_library_path()}" if loop is not None else f"stepping in Python: {_why_not()}"


@cache
def compiled() -> CompiledSteps | None:
    """The compiled loop, built on first use (None: stepping in Python; :func:`status` says why)."""
    if os.environ.get(ENV, "1").strip() == "0":
        _reasons.append(f"{ENV}=0")
        return None
    try:
        path = build()
        library = ctypes.CDLL(str(path))
        mj_step = ctypes.cast(ctypes.CDLL(str(_mujoco_library())).mj_step, ctypes.c_void_p).value
    except (OSError, RuntimeError, subprocess.SubprocessError) as e:
        _reasons.append(str(e))
        log.info("sigcore steps MuJoCo from Python, one step at a time (about 10 %% slower): %s", e)
        return None
    if mj_step is None:
        _reasons.append("mj_step not found in MuJoCo's library")
        return None
    return CompiledSteps(library, mj_step)


_reasons: list[str] = []


def _why_not() -> str:
    return _reasons[-1] if _reasons else "not tried yet"


def _mujoco_library() -> Path:
    """The MuJoCo shared library the bindings load (in the wheel's package directory)."""
    found = sorted(Path(mujoco.__file__).parent.glob("libmujoco.so*"))
    if not found:
        raise RuntimeError(f"no libmujoco.so* next to {mujoco.__file__}")
    return found[0]


def _headers() -> Path:
    include = Path(mujoco.__file__).parent / "include"
    if not (include / "mujoco" / "mjdata.h").is_file():
        raise RuntimeError(f"MuJoCo's C headers are not in {include} (the mujoco wheel ships them)")
    return include


def _cache_dir() -> Path:
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / "sigcore"


def _library_path() -> Path:
    digest = hashlib.sha256(SOURCE.read_bytes() + " ".join(FLAGS).encode()).hexdigest()[:16]
    return _cache_dir() / f"steps-mujoco{mujoco.__version__}-{digest}.so"


def _compiler() -> str:
    for name in (os.environ.get("CC", ""), "cc", "gcc", "clang"):
        if name and (found := shutil.which(name)):
            return found
    raise RuntimeError("no C compiler found (cc, gcc, clang or $CC); install one (Debian: apt-get install gcc) "
                       "to step faster")


def build() -> Path:
    """Compile ``_steps.c`` into the cache unless it is there already; returns the library's path.

    Written under a temporary name and renamed into place, so that processes building it at once (test workers)
    never load a half-written file.

    Raises:
        RuntimeError: no compiler, no headers, or the compiler failed (its output in the message).
    """
    path = _library_path()
    if path.is_file():
        return path
    cc, include = _compiler(), _headers()
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, suffix=".so.tmp")
    os.close(fd)
    try:
        done = subprocess.run([cc, *FLAGS, "-I", str(include), "-o", tmp, str(SOURCE)], capture_output=True,
                              text=True, timeout=120)
        if done.returncode != 0:
            raise RuntimeError(f"compiling {SOURCE.name} with {cc} failed: {done.stderr.strip()[-2000:]}")
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)
    return path


if __name__ == "__main__":  # scripts/setup.sh: build it now, say which loop runs
    print(status())
