"""Recording runs as rosbag2 directories with MCAP storage (``sigcore run --record``, ``sigcore bag``)."""

from .bag import BagWriter
from .bag_reading import BagInfo, bag_info, format_info
from .exceptions import BagError, RecordError
from .recorder import GROUND_TRUTH, GROUND_TRUTH_PREFIX, Recorder

__all__ = ["GROUND_TRUTH", "GROUND_TRUTH_PREFIX", "BagError", "BagInfo", "BagWriter", "RecordError", "Recorder",
           "bag_info", "format_info"]
