"""What handing every push to viser's event-loop thread costs the viewer's process (issue 28).

Usage: .venv/bin/python bench/viewer_handover.py [--pushes N] [--rounds R] [--smoke]
       --smoke: 1 round of 10 pushes, to check that the bench runs and prints every figure (tests/bench).

The viewer's process used to call viser from its push thread; a lost wake-up in viser (an ``asyncio.Event`` set from
that thread) could then stop a page's updates for good (docs/viewer.md, "One thread talks to viser"). Now
``Front.push`` hands the work to viser's event loop and waits for it. This bench builds a real viser server and a
``Front`` in this process, with the clean-up world's scene, and times N pushes of snapshots in which every frame
moved, two ways, alternating in each of R rounds:

* ``direct``: the same work called on this thread (what the push thread did before: ``Front._show``);
* ``handed``: ``Front.push``, through viser's event loop (what it does now).

It reports the median time per push of each way and their ratio per round (median and range). No browser is
connected: the pushes queue messages in viser's buffer, which is what a push costs the viewer's process.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import statistics
import time
from pathlib import Path

import numpy as np
import viser
from sigcore_viewer.front import Front
from sigcore_viewer.scenebuild import layout_of
from sigcore_viewer.snapshot import Snapshot

from sigcore.sim import Simulation
from sigcore.world import parse_world

ROOT = Path(__file__).resolve().parents[1]
OVERLAYS = {"names": True, "frames": False, "scan": False, "contacts": False, "map": True}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--pushes", type=int, default=300, help="pushes per way and round (default 300)")
    ap.add_argument("--rounds", type=int, default=7, help="rounds (default 7)")
    ap.add_argument("--smoke", action="store_true", help="1 round of 10 pushes: a check that the bench runs, not a "
                    "measurement")
    args = ap.parse_args()
    if args.smoke:
        args.rounds, args.pushes = 1, 10
    sim = Simulation(parse_world(ROOT / "worlds" / "cleanup.xml"), "mujoco")
    layout = layout_of(sim)
    poses = sim.backend.get_poses(layout.parts)
    names = list(sim.entities.names)
    with contextlib.redirect_stdout(io.StringIO()):  # viser's banner
        server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    posted: list[tuple[object, ...]] = []
    front = Front(server, posted.append, dict(OVERLAYS))
    counter = [0]

    def snap(first: bool = False) -> Snapshot:
        counter[0] += 1
        i = counter[0]
        moved = poses.copy()
        moved[:, 0] += 0.05 * np.sin(0.1 * i)  # every frame moved further than the viewer's threshold
        texts = {"score": f"score: {i}", "events": "", "result": "", "selection": "", "notes": ""}
        return Snapshot(i, 0.002 * i, time.perf_counter(), layout if first else None, moved, f"t = {i}", texts, [],
                        names)

    front.push(snap(first=True))
    ways = {"direct": lambda s: front._show(s), "handed": front.push}
    per_push: dict[str, list[float]] = {way: [] for way in ways}
    ratios: list[float] = []
    try:
        for r in range(args.rounds):
            order = list(ways) if r % 2 == 0 else list(reversed(ways))
            took: dict[str, float] = {}
            for way in order:
                snaps = [snap() for _ in range(args.pushes)]
                t0 = time.perf_counter()
                for s in snaps:
                    ways[way](s)
                took[way] = (time.perf_counter() - t0) / args.pushes
                per_push[way].append(took[way])
            ratios.append(took["handed"] / took["direct"])
            print(f"round {r + 1}: direct {took['direct'] * 1e3:.3f} ms, handed {took['handed'] * 1e3:.3f} ms "
                  f"per push, ratio {ratios[-1]:.3f}", flush=True)
    finally:
        front.stop()
        with contextlib.redirect_stdout(io.StringIO()):
            server.stop()
    direct, handed = statistics.median(per_push["direct"]), statistics.median(per_push["handed"])
    print(f"{len(layout.frames)} frames, {args.pushes} pushes x {args.rounds} rounds")
    print(f"median per push: direct {direct * 1e3:.3f} ms, handed {handed * 1e3:.3f} ms "
          f"(+{(handed - direct) * 1e6:.0f} us)")
    print(f"handed / direct: median {statistics.median(ratios):.3f} (range {min(ratios):.3f} to {max(ratios):.3f})")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
