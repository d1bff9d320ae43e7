"""Take the README's picture of the web viewer during the clean-up task: docs/images/viewer.png.

Runs ``sigcore run worlds/cleanup.xml --viewer --transport none --controller robot_000=cleanup.robot
--factor 3``, opens the page in a headless Chromium (sigcore_viewer.browser; needs chromium and chromium-driver),
pauses the run and takes the picture while the robot carries its second item (score 1100).
Usage: .venv/bin/python scripts/viewer_screenshot.py
"""

from __future__ import annotations

import socket
import subprocess
import sys
import time
from pathlib import Path

from sigcore_viewer.browser import Browser

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "docs" / "images" / "viewer.png"


def main() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    sim = subprocess.Popen([str(Path(sys.executable).parent / "sigcore"), "run", "worlds/cleanup.xml", "--transport",
                            "none", "--viewer", "--viewer-port", str(port), "--controller", "robot_000=cleanup.robot",
                            "--factor", "3", "--duration", "300", "-q"], cwd=ROOT, stdout=subprocess.DEVNULL)
    try:
        time.sleep(3)
        with Browser(f"http://127.0.0.1:{port}", 1400, 900) as page:
            page.wait(lambda p: "step" in p.text(), 60, "the page shows the run")
            page.screenshot()  # the first picture of a page waits for its textures (seconds)
            page.wait(lambda p: "score: 1100" in p.text(), 120, "the robot carries its second item")
            page.click("Pause")  # a picture can take seconds on a busy machine: the run waits for it
            page.wait(lambda p: "paused" in p.text(), 10, "the run pauses")
            page.dismiss_notifications()
            time.sleep(1.0)
            page.save(OUT)
    finally:
        sim.terminate()
        sim.wait(timeout=30)
    print(f"wrote {OUT.relative_to(ROOT)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
