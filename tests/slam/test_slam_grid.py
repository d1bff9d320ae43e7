"""The occupancy grid's ray tracing and the point-to-line refinement, on hand-made cases."""

from __future__ import annotations

import numpy as np
import pytest
from sigcore_slam import OccupancyGrid, Pose2
from sigcore_slam.linemap import LineMap


def test_one_beam_frees_its_path_and_marks_its_end() -> None:
    """A beam along +x from cell 0 to cell 5 frees cells 0..4 and marks cell 5; the rest stays unknown."""
    grid = OccupancyGrid(10, 3, 0.1, (0.0, 0.0))
    grid.integrate((0.05, 0.15), np.array([[0.55, 0.15]]), np.array([True]))
    data = grid.data()
    assert data[1, :5].tolist() == [40] * 5  # p = 1 / (1 + e^0.4)
    assert data[1, 5] == 70  # p = 1 / (1 + e^-0.85)
    assert (data[1, 6:] == -1).all() and (data[0] == -1).all() and (data[2] == -1).all()


def test_a_beam_without_return_only_frees() -> None:
    """A beam that hit nothing frees the cells up to its end and marks none occupied."""
    grid = OccupancyGrid(10, 10, 0.1, (0.0, 0.0))
    grid.integrate((0.05, 0.05), np.array([[0.95, 0.95]]), np.array([False]))
    data = grid.data()
    assert (data[np.arange(9), np.arange(9)] == 40).all()
    assert (data > 50).sum() == 0


def test_beams_leaving_the_grid_are_clipped() -> None:
    """Beams ending far outside the grid update cells up to its border and never index outside it."""
    grid = OccupancyGrid(20, 20, 0.1, (-1.0, -1.0))
    angles = np.linspace(-np.pi, np.pi, 360, endpoint=False)
    ends = 50.0 * np.stack([np.cos(angles), np.sin(angles)], axis=1)
    grid.integrate((0.0, 0.0), ends, np.ones(360, bool))
    data = grid.data()
    assert (data[0, :] == 40).all() and (data[:, 0] == 40).all() and (data[-1, :] == 40).all()
    assert (data == 70).sum() == 0  # the hits are outside


def test_repeated_hits_saturate_at_the_clamp() -> None:
    """Log-odds stay within [-clamp, clamp], so the occupancy never reaches exactly 0 or 100 when clamp is 3."""
    grid = OccupancyGrid(4, 1, 0.1, (0.0, 0.0), clamp=3.0)
    for _ in range(20):
        grid.integrate((0.05, 0.05), np.array([[0.35, 0.05]]), np.array([True]))
    assert grid.log_odds.max() == pytest.approx(3.0) and grid.log_odds.min() == pytest.approx(-3.0)
    assert grid.data()[0].tolist() == [5, 5, 5, 95]


def test_line_map_recovers_an_offset_against_two_walls() -> None:
    """Points on two perpendicular walls, shifted by (3, -2) cm and 0.01 rad, are aligned back within 1 mm."""
    lines = LineMap(50, 50, 0.2, (-5.0, -5.0))
    xs = np.linspace(-3.0, 3.0, 600)
    walls = np.concatenate([np.stack([xs, np.full_like(xs, 2.0)], axis=1),
                            np.stack([np.full_like(xs, 3.0), xs], axis=1)])
    lines.add(walls)
    truth = Pose2(0.2, -0.1, 0.3)
    scan = truth.inverse().apply(walls[::7])
    guess = truth @ Pose2(0.03, -0.02, 0.01)
    refined, used = lines.align(guess, scan)
    assert used > 100
    assert (refined.x, refined.y, refined.yaw) == pytest.approx((truth.x, truth.y, truth.yaw), abs=1e-3)


@pytest.mark.slow
def test_numba_loaded_only_with_a_grid() -> None:
    """Loading the plugin does not import numba (a world without SLAM pays nothing for it); a grid does."""
    import subprocess
    import sys

    code = ("import sys, sigcore_slam; print('numba' in sys.modules); "
            "sigcore_slam.OccupancyGrid(4, 4, 0.5, (0.0, 0.0)); print('numba' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.split()
    assert out == ["False", "True"]
