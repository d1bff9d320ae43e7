"""A headless Chromium showing a viewer page, driven like a person would: for tests, benches and screenshots.

Needs Debian's ``chromium`` and ``chromium-driver`` (``scripts/setup.sh`` installs them as root) and ``selenium``
(the test extra). Chromium renders WebGL in software (SwiftShader) here: the first picture takes about 10 s.
"""

from __future__ import annotations

import io
import shutil
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

from .exceptions import BrowserMissing

CHROMIUM = Path("/usr/bin/chromium")
CHROMEDRIVER = Path("/usr/bin/chromedriver")
FLAGS = ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
         "--disable-background-networking", "--disable-component-update", "--disable-sync", "--no-first-run",
         "--enable-unsafe-swiftshader")
FRAME_CAP = """(() => {
  const interval = 1000 / %r - 2, raf = window.requestAnimationFrame.bind(window);
  let drawn = -1e9;  // the timestamp of the last frame let through: every callback of that frame runs
  window.requestAnimationFrame = (callback) => raf((t) => {
    if (t === drawn || t - drawn >= interval) { drawn = t; callback(t); }
    else { window.requestAnimationFrame(callback); }
  });
})();"""
"""Installed in every page before its own scripts when ``max_fps`` is given: animation frames pass at most
``max_fps`` times a second (a frame's callbacks all run in the frame that passes); the others wait for the next."""


def missing() -> str | None:
    """What is missing to drive a browser here (the command that installs it), or None."""
    if not CHROMIUM.exists() or not CHROMEDRIVER.exists():
        return "chromium and chromium-driver are not installed (as root: apt-get install -y chromium chromium-driver)"
    try:
        import selenium  # noqa: F401
    except ImportError:
        return "selenium is not installed (pip install selenium, or pip install -e '.[test]')"
    return None


class Browser:
    """One headless Chromium window at ``url`` (``width`` x ``height`` pixels); :meth:`close` ends it.

    ``max_fps``: draw at most this many frames a second (:data:`FRAME_CAP`); None: as many as Chromium can. Drawing
    in software, Chromium takes about 1.4 of the 2 CPUs here however large the window (about 17 frames a second of a
    viewer page); at 5 frames a second, half of one (tests pass 5; the benches that measure the page pass none).

    Raises:
        BrowserMissing: what is missing (see :func:`missing`).
        ValueError: ``max_fps`` is not a positive number.
    """

    def __init__(self, url: str, width: int = 1280, height: int = 800, max_fps: float | None = None) -> None:
        if max_fps is not None and not 0 < max_fps < float("inf"):
            raise ValueError(f"max_fps must be a positive number of frames a second, or None; got {max_fps!r}")
        why = missing()
        if why is not None:
            raise BrowserMissing(why)
        from selenium import webdriver
        from selenium.webdriver.chrome.service import Service

        self._closed = False
        self._profile = tempfile.mkdtemp(prefix="sigcore-browser-")
        options = webdriver.ChromeOptions()
        for flag in (*FLAGS, f"--window-size={width},{height}", f"--user-data-dir={self._profile}"):
            options.add_argument(flag)
        options.set_capability("goog:loggingPrefs", {"browser": "ALL"})  # the page's console, for :meth:`console`
        self.driver: Any = webdriver.Chrome(service=Service(str(CHROMEDRIVER)), options=options)
        self.driver.set_page_load_timeout(60)
        if max_fps is not None:
            self.driver.execute_cdp_cmd("Page.addScriptToEvaluateOnNewDocument", {"source": FRAME_CAP % max_fps})
        self.driver.get(url)

    def close(self) -> None:
        """Quit the browser and remove its profile (again: nothing)."""
        if self._closed:
            return
        self._closed = True
        try:
            self.driver.quit()
        finally:
            shutil.rmtree(self._profile, ignore_errors=True)

    def __enter__(self) -> Browser:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # ------------------------------------------------------------------ looking
    def screenshot(self) -> np.ndarray:
        """The page as an (h, w, 3) uint8 RGB array."""
        from PIL import Image

        png = self.driver.get_screenshot_as_png()
        return np.asarray(Image.open(io.BytesIO(png)).convert("RGB"))

    def save(self, path: Path) -> None:
        """Write the page as a PNG file."""
        self.driver.save_screenshot(str(path))

    def text(self) -> str:
        """All the text of the page."""
        return str(self.driver.find_element("tag name", "body").text)

    def wait(self, predicate: Any, timeout: float, what: str) -> Any:
        """Poll ``predicate(self)`` every 0.2 s until it returns something (not None, False or empty);
        AssertionError naming ``what`` after ``timeout`` [s]."""
        end = time.monotonic() + timeout
        while True:
            value = predicate(self)
            if value is not None and value is not False and (not hasattr(value, "__len__") or len(value) > 0):
                return value
            if time.monotonic() > end:
                raise AssertionError(f"after {timeout:g} s: {what}; the page says:\n{self.text()[-1500:]}\n"
                                     f"the browser: {self.health()}")
            time.sleep(0.2)

    def console(self) -> list[str]:
        """What the page logged to its console since the last call (level and text, oldest first)."""
        try:
            return [f"{entry['level']}: {entry['message']}" for entry in self.driver.get_log("browser")]
        except Exception as e:  # a driver without logs: say so rather than fail the caller
            return [f"(no console: {type(e).__name__}: {e})"]

    def health(self) -> dict[str, Any]:
        """What tells a page that stopped updating from a server that stopped sending: whether the page still
        draws frames (viser applies its messages in the render loop), whether its WebGL context is lost, whether it
        is hidden, and its console's warnings and errors."""
        out: dict[str, Any] = {}
        try:
            self.driver.set_script_timeout(10)
            out["frames"] = self.driver.execute_async_script(
                "const done = arguments[arguments.length - 1];"
                "requestAnimationFrame(() => done('drawn'));"
                "setTimeout(() => done('no frame in 5 s'), 5000);")
            out["webgl"] = self.driver.execute_script(
                "const c = document.querySelector('canvas'); if (!c) return 'no canvas';"
                "const g = c.getContext('webgl2') || c.getContext('webgl');"
                "return !g ? 'no context' : g.isContextLost() ? 'context lost' : 'ok';")
            out["hidden"] = self.driver.execute_script("return document.hidden;")
            out["focus"] = self.driver.execute_script("return document.hasFocus();")
        except Exception as e:  # the page no longer answers: that is the finding
            out["script"] = f"{type(e).__name__}: {str(e)[:200]}"
        out["console"] = [line[:300] for line in self.console()
                          if not line.startswith("INFO") or "onnect" in line][-15:]  # errors, (dis)connections
        return out

    def dismiss_notifications(self) -> None:
        """Close the notes viser shows over the scene (e.g. "Software WebGL rendering detected")."""
        for button in self.driver.find_elements("css selector", ".mantine-Notification-closeButton"):
            try:
                button.click()
            except Exception:  # gone meanwhile
                pass

    # ------------------------------------------------------------------ acting
    def click(self, label: str) -> None:
        """Click the button labelled ``label``."""
        self.driver.find_element("xpath", f"//button[normalize-space()='{label}']").click()

    def field(self, label: str) -> Any:
        """The input next to the label ``label`` (a slider's: the number box beside it)."""
        return self.driver.find_element(
            "xpath", f"//label[normalize-space()='{label}']/ancestor::div[contains(@class,'mantine-Flex-root')][1]"
                     "//input[not(@type='hidden')]")

    def type(self, label: str, text: str) -> None:
        """Replace the text of the field labelled ``label`` by ``text``."""
        from selenium.webdriver.common.keys import Keys

        box = self.field(label)
        box.click()
        box.send_keys(Keys.CONTROL, "a")
        box.send_keys(text)

    def pick(self, label: str, option: str, timeout: float = 10.0) -> None:
        """Choose ``option`` in the list labelled ``label``."""
        self.field(label).click()
        xpath = f"//*[@role='option'][normalize-space()='{option}']"
        item = self.wait(lambda b: b.driver.find_elements("xpath", xpath), timeout, f"option {option!r} of {label}")
        item[0].click()
