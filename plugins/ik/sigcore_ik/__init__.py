"""sigcore's inverse kinematics feature (Pinocchio): registers :class:`IkFeature` as ``"ik"``.

Modules, one concept each: ``model`` (the Pinocchio model of a URDF), ``chain`` (arms), ``solver`` (damped least
squares), ``motion`` (moving an arm through its servos), ``robot`` (a robot's IK state in a simulation),
``feature`` (the ``ik`` feature), ``services`` and ``types`` (the API), ``exceptions``.
"""

from __future__ import annotations

from collections.abc import Callable

from sigcore.feature import Feature
from sigcore.plugins import hookimpl

from .feature import IkFeature

__all__ = ["IkFeature", "sigcore_register_features"]


@hookimpl
def sigcore_register_features(register: Callable[[type[Feature]], None]) -> None:
    """Register the IK feature under the name ``"ik"``."""
    register(IkFeature)
