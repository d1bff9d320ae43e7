"""Who holds what: the one record of grasps, kept by the simulation and changed only through its methods."""

from __future__ import annotations


class Grasps:
    """Every grasp, as ``(robot, gripper part) -> object`` and its inverse, always consistent."""

    def __init__(self) -> None:
        self._by_hand: dict[tuple[str, str], str] = {}
        self._by_object: dict[str, tuple[str, str]] = {}

    def hold(self, robot: str, part: str, obj: str) -> None:
        """Record that ``robot``'s gripper ``part`` holds ``obj``.

        Raises:
            ValueError: the gripper already holds something or the object is already held (callers check first).
        """
        if (robot, part) in self._by_hand or obj in self._by_object:
            raise ValueError(f"{robot}/{part} or {obj} is already in a grasp")
        self._by_hand[(robot, part)] = obj
        self._by_object[obj] = (robot, part)

    def release(self, robot: str, part: str) -> str | None:
        """Forget what ``robot``'s ``part`` holds; returns that object, or None if it held nothing."""
        obj = self._by_hand.pop((robot, part), None)
        if obj is not None:
            del self._by_object[obj]
        return obj

    def held_by(self, obj: str) -> tuple[str, str] | None:
        """``(robot, gripper part)`` holding ``obj``, or None."""
        return self._by_object.get(obj)

    def holding(self, robot: str, part: str) -> str | None:
        """The object ``robot``'s gripper ``part`` holds, or None."""
        return self._by_hand.get((robot, part))

    def is_held(self, obj: str) -> bool:
        """Whether some gripper holds ``obj``."""
        return obj in self._by_object

    def items(self) -> list[tuple[str, str, str]]:
        """Every grasp as ``(robot, part, object)``."""
        return [(robot, part, obj) for (robot, part), obj in self._by_hand.items()]

    def clear(self) -> None:
        """Forget every grasp (after a reset, which detached them in the backend)."""
        self._by_hand.clear()
        self._by_object.clear()

    def __len__(self) -> int:
        return len(self._by_hand)
