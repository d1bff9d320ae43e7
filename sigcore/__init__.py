"""sigcore: drive a physics simulation of robots, humans and objects through ROS 2 topics and services."""

from .errors import SigcoreError
from .plugins import hookimpl

__version__ = "0.1.0"
__all__ = ["SigcoreError", "__version__", "hookimpl"]
