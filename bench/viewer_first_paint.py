"""Time from loading the viewer's page to its first useful picture (issue 28).

Usage: .venv/bin/python bench/viewer_first_paint.py [--loads N] [--world WORLD] [--factor F] [--label TEXT] [--smoke]
       --smoke: 1 page load (--loads 1), to check that the bench runs and prints every figure (tests/bench).

One ``sigcore run WORLD --transport none --controller robot_000=cleanup.robot --viewer --factor F`` (the clean-up
task, the scripted robot moving, the viewer sending 30 updates a second) runs in a process of its own; a headless
Chromium 1280x800 (software WebGL: SwiftShader, no GPU, on the run's machine: everything shares its CPUs) loads the
page N times, each time in a fresh browser (nothing cached). A load is timed from its navigation start
(``performance.now()`` is 0 there) to:

* **panel**: the page's text shows the Run panel's status (``world ... · t = ... s``) and the Task panel's score;
* **scene**: the picture shows the room's walls across the scene (entities at their poses, not piled at the
  origin) and the robot's blue inside it;
* **useful**: both (the later of the two).

A script in the page (``PAGE_PROBE``, installed before the page's own) looks every 50 ms at the page's text and at
the scene's canvas (read back, scaled down) and notes the time of each, so that a page that keeps its main thread
busy for seconds is not timed by a poller that waits for it too. Before each load the run has been showing for at
least 2 s. Reports every load and the medians; ``--label`` names the run in the output.
The figures depend on the machine's load: the before/after figures in docs/benchmarks.md were taken back to back.

What the page waits for is printed too: the size of viser's initial scene (the messages a newly connected browser
is sent first, by kind), read from the viewer's server through a plain websocket client.
"""

from __future__ import annotations

import argparse
import os
import re
import signal
import socket
import statistics
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
STATUS = re.compile(r"world \S+ · t = \d+\.\d+ s")


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


PAGE_PROBE = r"""
(() => {
  const marks = window.__firstPaint = {};
  const mark = (k) => { if (!(k in marks)) marks[k] = performance.now() / 1000; };
  // the picture is read back from the scene's canvas: keep its drawing buffer (WebGL clears it otherwise)
  const getContext = HTMLCanvasElement.prototype.getContext;
  HTMLCanvasElement.prototype.getContext = function (kind, attrs) {
    if (kind === "webgl2" || kind === "webgl") attrs = Object.assign({}, attrs || {}, {preserveDrawingBuffer: true});
    return getContext.call(this, kind, attrs);
  };
  const small = document.createElement("canvas");
  small.width = 320; small.height = 200;
  const look = () => {
    const text = document.body ? document.body.innerText : "";
    if (/world \S+ · t = \d+\.\d+ s/.test(text) && text.includes("score:")) mark("panel");
    const canvas = [...document.querySelectorAll("canvas")].find((c) => c.width > 400);
    if (!canvas || "scene" in marks) return;
    const ctx = small.getContext("2d", {willReadFrequently: true});
    ctx.clearRect(0, 0, 320, 200);
    ctx.drawImage(canvas, 0, 0, 320, 200);
    const px = ctx.getImageData(0, 0, 225, 200).data;  // the left 70 %: the panel floats on the right
    let blue = 0, walls = 0, lo = 1e9, hi = -1; const wallCols = new Array(225).fill(0), blueCols = [];
    for (let i = 0; i < px.length; i += 4) {
      const r = px[i], g = px[i + 1], b = px[i + 2], x = (i / 4) % 225;
      if (b > 110 && b > r + 60 && b > g + 35) { blue++; blueCols.push(x); }
      if (r > 120 && r < 235 && r - b > 8 && r - b < 45 && Math.abs(r - g) < 16) { walls++; wallCols[x]++; }
    }
    for (let x = 0; x < 225; x++) if (wallCols[x] > 2) { lo = Math.min(lo, x); hi = Math.max(hi, x); }
    const inside = blueCols.filter((x) => x > lo && x < hi).length;
    if (walls > 300 && hi - lo > 110 && inside > 8) mark("scene");
  };
  setInterval(look, 50);
})();
"""
"""Runs in the page before its own scripts: marks (``performance.now()`` [s]) when the panel shows the run's status
and the score (``panel``), and when the scene's canvas shows the room (its walls across the picture, more than
half of the scene's width: entities at their poses, not piled at the origin) with the robot's blue inside
(``scene``). The canvas is read at 20 Hz (and never while the page's main thread is busy, when it cannot change)."""


def one_load(url: str, timeout: float) -> dict[str, float]:
    """Load the page in a fresh headless Chromium; the times [s] from its navigation start."""
    from sigcore_viewer.browser import Browser

    out: dict[str, float] = {}
    with Browser("about:blank") as page:
        driver = page.driver
        driver.set_page_load_timeout(timeout)
        driver.execute_cdp_cmd("Page.addScriptToEvaluateOnNewDocument", {"source": PAGE_PROBE})
        driver.get(url)
        out["load_event"] = driver.execute_script(
            "return performance.timing.loadEventEnd - performance.timing.navigationStart") / 1000.0
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            marks = driver.execute_script("return window.__firstPaint || {}")
            if "panel" in marks and "scene" in marks:
                break
            time.sleep(0.25)
        out.update({k: float(v) for k, v in marks.items()})
    if "panel" in out and "scene" in out:
        out["useful"] = max(out["panel"], out["scene"])
    return out


def initial_scene(port: int) -> tuple[dict[str, int], int, int]:
    """What viser sends a newly connected browser before anything new (up to its ``ReplayDoneMessage``): the
    messages by kind, the bytes on the wire and the bytes of binary arrays (meshes) among them."""
    import asyncio

    import msgspec
    import viser
    import websockets
    import zstandard

    async def read() -> tuple[dict[str, int], int, int]:
        kinds: dict[str, int] = {}
        wire = binary = 0
        protocol: Any = f"viser-v{viser.__version__}"
        async with websockets.connect(f"ws://127.0.0.1:{port}", subprotocols=[protocol], max_size=None) as ws:
            while True:
                raw = await asyncio.wait_for(ws.recv(), timeout=30)
                assert isinstance(raw, bytes)
                inner_len = int.from_bytes(raw[:8], "little")
                comp_len = int.from_bytes(raw[8:16], "little")
                inner = zstandard.ZstdDecompressor().decompress(raw[16:16 + comp_len], max_output_size=inner_len)
                window = msgspec.msgpack.decode(inner)
                wire += len(raw)
                binary += sum(window.get("binaryBufferLengths", ()))
                types = [m.get("type", "?") for m in window["messages"]]
                for kind in types:
                    kinds[kind] = kinds.get(kind, 0) + 1
                if "ReplayDoneMessage" in types:
                    return kinds, wire, binary

    return asyncio.run(read())


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--loads", type=int, default=5, help="page loads (each in a fresh browser)")
    ap.add_argument("--world", default=str(ROOT / "worlds" / "cleanup.xml"))
    ap.add_argument("--factor", type=float, default=0.5, help="the run's pace (the scripted task lasts 92 s)")
    ap.add_argument("--timeout", type=float, default=60.0, help="give a load up after this long [s]")
    ap.add_argument("--label", default="", help="a name for this run in the report")
    ap.add_argument("--no-scene-size", action="store_true", help="do not read the initial scene's size")
    ap.add_argument("--smoke", action="store_true", help="1 page load: a check that the bench runs, not a "
                    "measurement")
    args = ap.parse_args()
    if args.smoke:
        args.loads = 1
    port = free_port()
    log = Path(f"/tmp/viewer_first_paint_{os.getpid()}.log")
    with log.open("w") as out:
        run = subprocess.Popen([sys.executable, "-m", "sigcore", "run", args.world, "--transport", "none",
                                "--controller", "robot_000=cleanup.robot", "--viewer", "--viewer-port", str(port),
                                "--factor", str(args.factor), "-q", "--viewer-linger", "0"],
                               cwd=ROOT, stdout=out, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL,
                               start_new_session=True)
    try:
        end = time.monotonic() + 120
        while "ready:" not in log.read_text():
            if run.poll() is not None or time.monotonic() > end:
                print(log.read_text(), file=sys.stderr)
                return 1
            time.sleep(0.2)
        time.sleep(2.0)
        url = f"http://127.0.0.1:{port}"
        if not args.no_scene_size:
            try:
                kinds, wire, binary = initial_scene(port)
                top = sorted(kinds.items(), key=lambda kv: -kv[1])[:8]
                print(f"initial scene: {sum(kinds.values())} messages, {wire / 1024:.0f} KiB on the wire "
                      f"({binary / 1024:.0f} KiB of arrays); " + ", ".join(f"{k} {n}" for k, n in top), flush=True)
            except Exception as e:  # the figure is a diagnostic: the timing goes on without it
                print(f"initial scene: not read ({type(e).__name__}: {e})")
        loads = []
        for i in range(args.loads):
            if run.poll() is not None:
                print("the run ended before every load was done; use a lower --factor", file=sys.stderr)
                break
            t = one_load(url, args.timeout)
            loads.append(t)
            print(f"load {i + 1}: " + ", ".join(f"{k} {v:.2f} s" for k, v in t.items()), flush=True)
        for key in ("load_event", "panel", "scene", "useful"):
            values = [t[key] for t in loads if key in t]
            missing = len(loads) - len(values)
            if values:
                print(f"{args.label + ': ' if args.label else ''}{key}: median {statistics.median(values):.2f} s "
                      f"(min {min(values):.2f}, max {max(values):.2f}; {len(values)} loads"
                      f"{f', {missing} never within the timeout' if missing else ''})")
    finally:
        if run.poll() is None:
            os.killpg(run.pid, signal.SIGINT)
            try:
                run.wait(timeout=20)
            except subprocess.TimeoutExpired:
                os.killpg(run.pid, signal.SIGKILL)
                run.wait()
        log.unlink(missing_ok=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
