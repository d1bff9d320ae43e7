"""``sigcore view``: a world opened in the web viewer, paused at t = 0 (a ``sigcore run --viewer --paused``), or a
recording played back in it."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from ..isolation import CALLBACK_BUDGET
from .common import Controllers, Seed, ViewerHost, ViewerPort, ViewerRate, check_backend, err, fail
from .run import run, start_viewer
from .transport import DEFAULT_TRANSPORT


def view(
    world_file: Annotated[Path, typer.Argument(
        exists=True, help="world XML file, or a recording: a directory made by sigcore run --record (or its .mcap)")],
    backend: Annotated[str, typer.Option(help="physics backend", callback=check_backend)] = "mujoco",
    transport: Annotated[str | None, typer.Option(
        help=f"transport plugin; default '{DEFAULT_TRANSPORT}' when installed; 'none': the viewer alone")] = None,
    controller: Controllers = None,
    viewer_host: ViewerHost = "127.0.0.1",
    viewer_port: ViewerPort = None,
    viewer_rate: ViewerRate = 30.0,
    seed: Seed = None,
) -> None:
    """Open a world in the web viewer, paused at t = 0: press play in the browser (= sigcore run WORLD --viewer
    --paused). The transport (ROS 2 by default) runs beside it; Ctrl-C ends the run and prints the results.
    Given a recording (sigcore run --record DIR), the viewer plays it back with a timeline to scrub (with the seed
    the run was drawn with)."""
    if world_file.is_dir() or world_file.suffix == ".mcap":
        if seed is not None:
            raise fail(["--seed is for a world file: a recording is shown with the seed it was recorded with"])
        _view_recording(world_file, viewer_host, viewer_port, viewer_rate)
        return
    run(world_file, backend=backend, duration=None, steps=None, fast=False, realtime=False, factor=None,
        paused=True, wait_for=None, wait_timeout=0.0, transport=transport, quiet=True, controller=controller,
        callback_budget=CALLBACK_BUDGET, disable_slow_controllers=False, worlds=None, viewer=True,
        viewer_host=viewer_host, viewer_port=viewer_port, viewer_rate=viewer_rate, seed=seed)


def _view_recording(path: Path, host: str, port: int | None, rate: float) -> None:
    """``sigcore view DIR``: check the recording, open the viewer, play it back until Ctrl-C."""
    import signal

    from ..errors import ViewerError
    from ..record import BagError, bag_info

    try:
        info = bag_info(path)
    except BagError as e:
        raise fail([f"sigcore view: {e}"]) from None
    for problem in info.problems:
        err.print(f"sigcore view: warning: {problem}; showing what is readable")
    viewer = start_viewer(True, host, port, rate)
    assert viewer is not None
    stop = {"now": False}

    def interrupted(*_: object) -> None:
        stop["now"] = True

    previous = {sig: signal.signal(sig, interrupted) for sig in (signal.SIGINT, signal.SIGTERM)}
    err.print(f"ready: viewer at {viewer.url} shows {path} ({(info.end_ns - info.start_ns) / 1e9:.2f} s recorded); "
              "Ctrl-C ends it", markup=False, soft_wrap=True)
    try:
        viewer.play_recording(path, lambda: stop["now"])
    except ViewerError as e:
        raise fail([f"sigcore view: {e}"]) from None
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)
        viewer.stop()
