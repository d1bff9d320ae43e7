"""The SLAM feature's agent API: the ``<robot>_save_map`` service (types generated into ``sigcore_msgs``)."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from pydantic import Field

from sigcore.agent.exceptions import ApiError
from sigcore.api.table import ROBOT, ApiEntry
from sigcore.api.types import ApiModel

if TYPE_CHECKING:
    from sigcore.sim.simulation import Simulation


class SaveMapRequest(ApiModel):
    """Save the SLAM occupancy grid as `path`.pgm and `path`.yaml (map_server format; relative to the simulator's
    working directory)."""

    path: str = Field(default="", description="base name of the files, e.g. /tmp/cleanup_map")


class SaveMapResponse(ApiModel):
    """The YAML file written [absolute path]."""

    yaml_file: str = ""
    success: bool = False
    message: str = ""


def save_map(sim: Simulation, agent: str, request: Any) -> dict[str, Any]:
    """Handler of ``_save_map``: refuses robots that are not mapped and empty paths."""
    from .feature import SlamFeature

    feature = sim.features.get(SlamFeature.name)
    if not isinstance(feature, SlamFeature) or feature.robot != agent:
        mapped = feature.robot if isinstance(feature, SlamFeature) else "none"
        raise ApiError(f"robot '{agent}' has no SLAM map; mapped robot: {mapped} "
                       f"(enable with <plugin name=\"slam\" agent=\"{agent}\"/>)")
    if not request.path.strip():
        raise ApiError("path is empty; give a base name such as /tmp/map (writes /tmp/map.pgm and /tmp/map.yaml)")
    try:
        written = feature.save_map(request.path)
    except OSError as e:
        raise ApiError(f"cannot write the map to '{request.path}': {e}") from None
    return {"yaml_file": str(written.resolve())}


def entries() -> list[ApiEntry]:
    """The API entries of the ``slam`` feature."""
    return [ApiEntry("_save_map", "service", "SaveMap", SaveMapRequest, SaveMapResponse, ROBOT, save_map,
                     "save the SLAM occupancy grid as PGM + YAML (map_server format)", origin="slam")]
