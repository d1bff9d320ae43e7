"""Saving the map in map_server format (PGM + YAML), loading it back, and the <robot>_save_map service."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from sigcore_slam import SlamFeature, load_map, save_map
from sigcore_slam.mapfile import trinary
from slam_room import ROBOT, drive_to

from sigcore.api.call import call_and_wait
from sigcore.api.table import ApiEntry
from sigcore.sim import Simulation


def _entry(sim: Simulation) -> ApiEntry:
    return next(e for e in sim.api_entries() if e.suffix == "_save_map")


def test_saved_map_loads_back_identically(room_sim: Simulation, tmp_path: Path) -> None:
    """The loaded array equals the grid thresholded as map_server does; saving it again gives the same bytes."""
    drive_to(room_sim, [(1.0, -0.8)])
    slam = room_sim.features["slam"]
    assert isinstance(slam, SlamFeature)
    yaml = slam.save_map(tmp_path / "room")
    assert yaml == tmp_path / "room.yaml"
    loaded = load_map(yaml)
    expected = trinary(slam.grid.data())
    assert loaded.data.dtype == np.int8 and loaded.data.shape == expected.shape
    assert np.array_equal(loaded.data, expected)
    assert (expected == 100).sum() > 100 and (expected == 0).sum() > 1000 and (expected == -1).sum() > 1000
    assert loaded.resolution == slam.grid.resolution
    assert loaded.origin == (*slam.grid.origin, 0.0)
    again = save_map(tmp_path / "again", loaded.data, loaded.resolution, loaded.origin[:2])
    assert (tmp_path / "again.pgm").read_bytes() == (tmp_path / "room.pgm").read_bytes()
    assert again.read_text() == yaml.read_text().replace("room.pgm", "again.pgm")


def test_pgm_rows_run_from_the_top_of_the_map(tmp_path: Path) -> None:
    """Row 0 of the grid (lowest y) is the PGM's last row; occupied is black, free white, unknown grey 205."""
    data = np.full((3, 4), -1, np.int8)
    data[0, :] = 100
    data[2, :] = 0
    save_map(tmp_path / "m.yaml", data, 0.1, (-1.0, 2.0))
    raw = (tmp_path / "m.pgm").read_bytes()
    pixels = np.frombuffer(raw[-12:], np.uint8).reshape(3, 4)
    assert pixels[:, 0].tolist() == [254, 205, 0]
    text = (tmp_path / "m.yaml").read_text()
    assert "image: m.pgm" in text and "origin: [-1.0, 2.0, 0.0]" in text and "mode: trinary" in text


def test_load_rejects_a_non_pgm_image(tmp_path: Path) -> None:
    """A map YAML pointing at something other than a binary 8-bit PGM is a ValueError naming the file."""
    (tmp_path / "m.pgm").write_bytes(b"P2\n2 2\n255\n0 0 0 0\n")
    (tmp_path / "m.yaml").write_text("image: m.pgm\nresolution: 0.05\norigin: [0, 0, 0]\nnegate: 0\n"
                                     "occupied_thresh: 0.65\nfree_thresh: 0.196\n")
    with pytest.raises(ValueError, match="m.pgm: not a binary 8-bit PGM"):
        load_map(tmp_path / "m.yaml")


def test_save_map_service(room_sim: Simulation, tmp_path: Path) -> None:
    """<robot>_save_map writes the files and answers their path; an empty path is refused with a reason."""
    room_sim.step(200)
    entry = _entry(room_sim)
    assert (entry.direction, entry.ros_type, entry.origin) == ("service", "SaveMap", "slam")
    ok = call_and_wait(room_sim, entry, ROBOT, {"path": str(tmp_path / "svc" / "map")})
    assert ok["success"], ok["message"]
    assert ok["yaml_file"] == str((tmp_path / "svc" / "map.yaml").resolve())
    assert load_map(ok["yaml_file"]).data.shape == (200, 200)
    refused = call_and_wait(room_sim, entry, ROBOT, {"path": ""})
    assert not refused["success"] and "path is empty" in refused["message"]
    bad = call_and_wait(room_sim, entry, ROBOT, {"path": 3})
    assert not bad["success"]
