"""QoS of every topic: REP-2003 defaults, overridable per topic from the world file.

- sensor data (LaserScan): reliable, volatile, keep last 5 (REP-2003: drivers publish with the system default;
  consumers subscribe with ``SensorDataQoS``, best effort, which matches a reliable publisher);
- ``/clock``: reliable, volatile, keep last 1 (matches rclcpp's best-effort ``ClockQoS`` and reliable readers);
- ``/tf``: reliable, volatile, keep last 100; ``/tf_static`` and ``/sigcore/ready``: reliable, transient local,
  keep last 1 (latched);
- odometry, joint states, sig_ros events and commands: reliable, volatile, keep last 10.
"""

from __future__ import annotations

from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

from .config import QosOverride


def _profile(depth: int, reliable: bool = True, latched: bool = False) -> QoSProfile:
    return QoSProfile(
        history=HistoryPolicy.KEEP_LAST, depth=depth,
        reliability=ReliabilityPolicy.RELIABLE if reliable else ReliabilityPolicy.BEST_EFFORT,
        durability=DurabilityPolicy.TRANSIENT_LOCAL if latched else DurabilityPolicy.VOLATILE)


class Qos:
    """QoS profiles by topic; an override from the world (``qos="/clock: best_effort"``) wins.

    Args:
        overrides: Overrides by absolute topic name.
    """

    def __init__(self, overrides: dict[str, QosOverride]) -> None:
        self.overrides = overrides
        self.used: set[str] = set()

    def _get(self, topic: str, default: QoSProfile) -> QoSProfile:
        key = topic if topic.startswith("/") else "/" + topic
        o = self.overrides.get(key)
        if o is None:
            return default
        self.used.add(key)
        profile = QoSProfile(history=default.history, depth=default.depth, reliability=default.reliability,
                             durability=default.durability)
        if o.reliable is not None:
            profile.reliability = ReliabilityPolicy.RELIABLE if o.reliable else ReliabilityPolicy.BEST_EFFORT
        if o.transient_local is not None:
            profile.durability = (DurabilityPolicy.TRANSIENT_LOCAL if o.transient_local
                                  else DurabilityPolicy.VOLATILE)
        if o.depth is not None:
            if o.depth == 0:
                profile.history = HistoryPolicy.KEEP_ALL
            else:
                profile.history, profile.depth = HistoryPolicy.KEEP_LAST, o.depth
        return profile

    def sensor(self, topic: str) -> QoSProfile:
        """Raw sensor data (REP-2003: published with the system default, reliable and volatile)."""
        return self._get(topic, _profile(5))

    def clock(self, topic: str = "/clock") -> QoSProfile:
        """The simulation clock."""
        return self._get(topic, _profile(1))

    def tf(self, topic: str = "/tf") -> QoSProfile:
        """Dynamic transforms."""
        return self._get(topic, _profile(100))

    def latched(self, topic: str) -> QoSProfile:
        """Transient-local topics: /tf_static, readiness."""
        return self._get(topic, _profile(1, latched=True))

    def state(self, topic: str) -> QoSProfile:
        """Odometry and joint states."""
        return self._get(topic, _profile(10))

    def events(self, topic: str) -> QoSProfile:
        """Event topics (collisions, messages): reliable so none is lost."""
        return self._get(topic, _profile(50))

    def commands(self, topic: str) -> QoSProfile:
        """Subscribed command topics."""
        return self._get(topic, _profile(10))

    def unused(self) -> list[str]:
        """Overrides that named no topic of this world (probably a typo)."""
        return sorted(set(self.overrides) - self.used)
