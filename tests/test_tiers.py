"""The suite's tiers and its parallel run (``tests/tiers.py``, ``tests/rosdomains.py``): parallel workers never share
a ROS 2 domain, a module's module-scoped fixture is built once however many workers run, the longest work is handed
out first, and a test file that starts ROS 2 nodes or a browser says so with its marker (the fast tier leaves it out).
"""

from __future__ import annotations

import subprocess
import sys
import textwrap
from pathlib import Path

import pytest
import rosdomains

HERE = Path(__file__).parent

ROS2_SIGNS = ("rosproc", "start_sim(", "start_in_process(", "Ros2Transport(", "run_task.py", '"--transport", "ros2"')
"""Text that shows a test file starts ROS 2 nodes."""
BROWSER_SIGNS = ("Browser(",)
"""Text that shows a test file drives a browser."""


def test_workers_have_disjoint_ros_domain_ranges(monkeypatch: pytest.MonkeyPatch) -> None:
    """Each of the WORKERS xdist workers draws its domains from a range of its own inside 1-96 (below the benches'
    101- and sigcore eval's 120-232), and successive draws in one worker differ."""
    ranges = []
    for worker in range(rosdomains.WORKERS):
        monkeypatch.setenv("PYTEST_XDIST_WORKER", f"gw{worker}")
        drawn = [rosdomains.next_domain() for _ in range(2 * rosdomains.SPAN)]
        assert all(a != b for a, b in zip(drawn, drawn[1:], strict=False))
        assert set(drawn) == set(range(1 + worker * rosdomains.SPAN, 1 + (worker + 1) * rosdomains.SPAN))
        ranges.append(set(drawn))
    everything = set().union(*ranges)
    assert len(everything) == sum(len(r) for r in ranges) and max(everything) <= 96 and min(everything) >= 1
    monkeypatch.delenv("PYTEST_XDIST_WORKER")
    assert 1 <= rosdomains.next_domain() <= rosdomains.SPAN  # without xdist: worker 0's range


@pytest.mark.parametrize("path", sorted(HERE.rglob("test_*.py")), ids=lambda p: str(p.relative_to(HERE)))
def test_a_file_that_starts_ros2_or_a_browser_is_marked(path: Path) -> None:
    """A test file whose text starts ROS 2 nodes (a simulation over ROS 2, the clean-up task's run_task.py, a
    transport in-process) carries the ``ros2`` marker, one that opens a browser the ``browser`` marker: the fast
    tier, ``-m "not slow and not ros2 and not browser"``, leaves them out. A line that only looks so says "starts no
    ROS 2 nodes"."""
    if path == Path(__file__):
        return
    text = path.read_text()
    if any(sign in line and "starts no ROS 2 nodes" not in line for line in text.splitlines() for sign in ROS2_SIGNS):
        assert "pytest.mark.ros2" in text or "needs_ros" in text, f"{path.name} starts ROS 2 nodes: mark it ros2"
    if any(sign in text for sign in BROWSER_SIGNS):
        assert "pytest.mark.browser" in text, f"{path.name} opens a browser: mark it browser"


@pytest.mark.slow
def test_a_module_scoped_fixture_is_built_once_and_long_work_goes_first(tmp_path: Path) -> None:
    """Under ``-n 2 --dist loadgroup`` (the suite's settings) a module-scoped fixture used by six tests is built once
    (pytest-xdist 3.8's own grouping does nothing under pytest 9: tests/tiers.py groups them), while tests without
    such a fixture spread over both workers; the test measured longest in durations.json starts first."""
    (tmp_path / "pytest.ini").write_text("[pytest]\n")
    (tmp_path / "conftest.py").write_text(textwrap.dedent(f"""
        import sys
        sys.path.insert(0, {str(HERE)!r})
        import pytest
        import tiers
        tiers.DURATIONS = tiers.Path({str(tmp_path / "durations.json")!r})

        @pytest.hookimpl(tryfirst=True)
        def pytest_collection_modifyitems(config, items):
            tiers.arrange(config, items)
        """))
    (tmp_path / "durations.json").write_text('{"modules": ["test_loose.py"], "seconds": {"test_loose.py::test_z": 9}}')
    (tmp_path / "test_grouped.py").write_text(textwrap.dedent(f"""
        import os, time
        import pytest

        @pytest.fixture(scope="module")
        def built():
            with open({str(tmp_path / "built.txt")!r}, "a") as f:
                f.write(os.environ["PYTEST_XDIST_WORKER"] + "\\n")

        @pytest.mark.parametrize("i", range(6))
        def test_uses(built, i):
            time.sleep(0.2)
        """))
    (tmp_path / "test_loose.py").write_text(textwrap.dedent(f"""
        import os, time
        import pytest

        def _note(name):
            with open({str(tmp_path / "loose.txt")!r}, "a") as f:
                f.write(name + " " + os.environ["PYTEST_XDIST_WORKER"] + "\\n")

        @pytest.mark.parametrize("i", range(6))
        def test_loose(i):
            _note(f"loose{{i}}")
            time.sleep(0.3)

        def test_z():
            _note("z")
        """))
    r = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "-n", "2", "--dist",
                        "loadgroup", "--no-loadscope-reorder", "-c", str(tmp_path / "pytest.ini"),
                        str(tmp_path)], capture_output=True, text=True, timeout=120,
                       cwd=tmp_path)
    assert r.returncode == 0 and "13 passed" in r.stdout, r.stdout[-3000:] + r.stderr[-3000:]
    assert len((tmp_path / "built.txt").read_text().split()) == 1
    loose = [line.split() for line in (tmp_path / "loose.txt").read_text().splitlines()]
    assert len({worker for _, worker in loose}) == 2, loose
    assert loose[0][0] == "z", loose
