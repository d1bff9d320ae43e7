"""The simulation: clock, fixed-step loop, event dispatch, run modes."""

from .dispatch import ControllerFailure
from .exceptions import FeatureError, SimulationError
from .lidar import LidarSensor, Scan
from .runner import RunReport, run
from .simulation import Simulation

__all__ = ["ControllerFailure", "FeatureError", "LidarSensor", "RunReport", "Scan", "Simulation", "SimulationError",
           "run"]
