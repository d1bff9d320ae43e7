"""Each package keeps its errors in one module (issue 29, item 8): ``sigcore/errors.py`` for the top level, each
subpackage's and each bundled plugin's ``exceptions.py``; every error derives from ``SigcoreError``;
``WorldRefusal`` is not a kind of ``SpawnRefusal``; there is one ``UnreachableError``."""

from __future__ import annotations

import importlib
import inspect
import pkgutil
from types import ModuleType

import pytest

from sigcore.agent.exceptions import UnreachableError
from sigcore.errors import SigcoreError
from sigcore.world.exceptions import Refusal, SpawnRefusal, WorldRefusal

PACKAGES = ["sigcore", "sigcore_backend_mujoco", "sigcore_backend_bullet", "sigcore_ik", "sigcore_referee",
            "sigcore_ros2", "sigcore_slam", "sigcore_viewer"]
HOMES = ("errors", "exceptions")
"""The names an error's module may have (its last part)."""


def modules() -> list[ModuleType]:
    """Every module of sigcore and of the bundled plugins (the writer process's own module excepted: it imports
    nothing of sigcore)."""
    out = []
    for name in PACKAGES:
        package = importlib.import_module(name)
        out.append(package)
        for info in pkgutil.walk_packages(package.__path__, f"{name}."):
            if info.name.endswith("_writer") or ".__main__" in info.name:
                continue
            out.append(importlib.import_module(info.name))
    return out


def errors_by_module() -> dict[str, list[type[BaseException]]]:
    found: dict[str, list[type[BaseException]]] = {}
    for module in modules():
        for _, cls in inspect.getmembers(module, inspect.isclass):
            if issubclass(cls, BaseException) and cls.__module__ == module.__name__:
                found.setdefault(module.__name__, []).append(cls)
    return found


def test_every_error_lives_in_its_packages_exceptions_module() -> None:
    misplaced = {module: sorted(c.__name__ for c in classes) for module, classes in errors_by_module().items()
                 if module.rsplit(".", 1)[-1] not in HOMES
                 and any(not c.__name__.startswith("_") for c in classes)}
    assert misplaced == {}


def test_every_error_is_a_sigcore_error() -> None:
    foreign = [f"{c.__module__}.{c.__name__}" for classes in errors_by_module().values() for c in classes
               if not issubclass(c, SigcoreError) and not c.__name__.startswith("_")]
    assert foreign == []


def test_the_scan_finds_the_errors() -> None:
    found = errors_by_module()
    assert SpawnRefusal in found["sigcore.world.exceptions"] and UnreachableError in found["sigcore.agent.exceptions"]
    assert len(found) >= 10


def test_a_world_refusal_is_no_spawn_refusal() -> None:
    assert not issubclass(WorldRefusal, SpawnRefusal) and not issubclass(SpawnRefusal, WorldRefusal)
    assert issubclass(WorldRefusal, Refusal) and issubclass(SpawnRefusal, Refusal)
    with pytest.raises(WorldRefusal):
        try:
            raise WorldRefusal("NOT_FOUND", "no such world")
        except SpawnRefusal:  # a spawn's handler does not take a world's refusal
            pytest.fail("a WorldRefusal was caught as a SpawnRefusal")


def test_there_is_one_unreachable_error() -> None:
    """The referee's example arm and the IK feature raise the core's UnreachableError (IK's, with the closest
    configuration, is a kind of it)."""
    named = [c for classes in errors_by_module().values() for c in classes if c.__name__ == "UnreachableError"]
    assert named == [UnreachableError]
    from sigcore_ik.exceptions import NoSolutionError
    from sigcore_referee.arm import hand_down

    assert issubclass(NoSolutionError, UnreachableError)
    with pytest.raises(UnreachableError, match="from the l wrist"):
        hand_down("l", 5.0, 0.0, 1.0)
