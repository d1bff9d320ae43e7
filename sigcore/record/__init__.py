"""Recording runs as rosbag2 directories with MCAP storage (``sigcore run --record``, ``sigcore bag``)."""

from .bag import BagError, BagInfo, BagWriter, bag_info, format_info
from .recorder import GROUND_TRUTH, GROUND_TRUTH_PREFIX, Recorder, RecordError

__all__ = ["GROUND_TRUTH", "GROUND_TRUTH_PREFIX", "BagError", "BagInfo", "BagWriter", "RecordError", "Recorder",
           "bag_info", "format_info"]
