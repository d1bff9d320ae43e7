"""sigcore: drive a physics simulation of robots, humans and objects through ROS 2 topics and services."""

from .plugins import hookimpl

__version__ = "0.1.0"
__all__ = ["__version__", "hookimpl"]
