"""Agents: controllers with the SIGVerse lifecycle and the SimObj/RobotObj handle API."""

from .controller import Controller
from .events import CollisionEvent, Message
from .exceptions import ApiError, ControllerError, GraspError, GraspRefusal
from .handle import SimObj
from .robot import RobotObj

__all__ = ["ApiError", "CollisionEvent", "Controller", "ControllerError", "GraspError", "GraspRefusal", "Message",
           "RobotObj", "SimObj"]
