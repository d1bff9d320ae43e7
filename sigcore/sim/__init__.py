"""The simulation: clock, fixed-step loop, event dispatch, run modes."""

from .dispatch import ControllerFailure, SlowCallbacks
from .exceptions import FeatureError, SimulationError
from .feature_guard import FeatureFailure
from .lidar import LidarSensor, Scan
from .runner import RunReport, run
from .simulation import Simulation

__all__ = ["ControllerFailure", "FeatureError", "FeatureFailure", "LidarSensor", "RunReport", "Scan", "Simulation",
           "SimulationError", "SlowCallbacks", "run"]
