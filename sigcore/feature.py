"""The feature interface: world-level add-ons enabled with ``<plugin name=...>`` (SLAM, IK, referee...)."""

from __future__ import annotations

from abc import ABC, abstractmethod
from typing import TYPE_CHECKING, ClassVar

from pydantic import BaseModel, ConfigDict

if TYPE_CHECKING:
    from .api.table import ApiEntry
    from .sim.simulation import Simulation
    from .sim.spawn import EntityChange


class FeatureConfig(BaseModel):
    """Base of a feature's configuration model: the attributes of its ``<plugin>`` element, one field each.

    Strict (unknown fields are errors) and frozen. Attribute values arrive as strings from the XML; pydantic parses
    numbers (``"0.2"``) and booleans (``"true"``, ``"false"``); lists need a ``BeforeValidator`` that splits the
    string (e.g. ``sigcore.world.models.Floats``, ``Tags``). Put units in field descriptions (``"... in [s]"``): the
    world file's messages show them. A cross-field rule is a ``model_validator`` raising
    :class:`sigcore.world.exceptions.FieldError` to blame one attribute.
    """

    model_config = ConfigDict(extra="forbid", frozen=True, str_strip_whitespace=True, allow_inf_nan=False)


class NoConfig(FeatureConfig):
    """The configuration of a feature that takes no attributes besides ``name``."""


class Feature(ABC):
    """A feature of one simulation, configured by the attributes of its ``<plugin>`` element.

    The core validates those attributes against :attr:`config_model` (every problem located at its
    ``file:line:column``) and passes the validated instance to the constructor.
    """

    name: ClassVar[str]
    config_model: ClassVar[type[BaseModel]] = NoConfig
    """The pydantic model of the ``<plugin>`` attributes (``name`` excluded); a :class:`FeatureConfig` subclass."""

    @classmethod
    def api_entries(cls) -> list[ApiEntry]:
        """Endpoints this feature adds to every agent of the listed kinds (e.g. ``_ik`` for robots). Their types
        must be in an interface package: bundled features' types are generated into ``sigcore_msgs``."""
        return []

    @classmethod
    def message_types(cls) -> list[type[BaseModel]]:
        """The ``sigcore_msgs`` message types of this feature's publications (declared through
        ``sim.publications``; bundled features' types are generated into ``sigcore_msgs``)."""
        return []

    @abstractmethod
    def __init__(self, sim: Simulation, config: BaseModel) -> None:
        """Attach to ``sim``: subscribe to its events (e.g. ``sim.events.subscribe("step", self._on_step)``; what
        is subscribed here is this feature's, detached if it fails and when its world is unloaded).

        Args:
            sim: The simulation being built.
            config: The ``<plugin>`` attributes, validated: an instance of :attr:`config_model` (subclasses
                annotate it with their own model).

        Raises:
            sigcore.world.exceptions.FieldError: an attribute is wrong for this world (e.g. ``agent`` names no
                robot); the core reports it at that attribute's ``file:line:column``. A plain ``ValueError`` is
                reported at the ``<plugin>`` element.
        """

    def summary(self) -> dict[str, object]:
        """Figures to print at the end of a run (e.g. a score)."""
        return {}

    def report(self) -> list[str]:
        """Lines printed as they are after the summaries at the end of a run (e.g. a score table); none by default."""
        return []

    def results(self) -> dict[str, object]:
        """What a program reading the run's results needs (``sigcore run --results FILE``, ``sigcore eval``):
        JSON-able values only. By default :meth:`summary`; a feature adds what it keeps for people in its
        :meth:`report` (e.g. the referee's events)."""
        return self.summary()

    def outcome(self) -> bool | None:
        """Whether the world's task succeeded, for the exit code of ``sigcore run`` (1 if any feature says False);
        ``None``: no verdict (the default, or the task has not ended)."""
        return None

    def entities_changed(self, change: EntityChange) -> None:
        """Entities were added or removed while running (spawned, deleted): ``change.added`` are in
        ``sim.entities`` and the backend now, ``change.removed`` are gone. Called on the simulation thread between
        steps, after the core's own state was updated; the default does nothing."""
        return None

    def reset(self) -> None:
        """Called by :meth:`Simulation.reset` after the backend's state was restored; forget per-run state."""
        return None
