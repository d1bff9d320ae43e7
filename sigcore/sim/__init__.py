"""The simulation: clock, fixed-step loop, event dispatch, run modes."""

from .control import ControlChange, RunControl
from .dispatch import ControllerFailure, SlowCallbacks
from .exceptions import FeatureError, RunStateError, SimulationError
from .features import FeatureFailure
from .lidar import LidarSensor, Scan
from .runner import RunReport, run
from .simulation import Simulation

__all__ = ["ControlChange", "ControllerFailure", "FeatureError", "FeatureFailure", "LidarSensor", "RunControl",
           "RunReport", "RunStateError", "Scan", "Simulation", "SimulationError", "SlowCallbacks", "run"]
