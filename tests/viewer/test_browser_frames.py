"""The tests' browser draws at most ``max_fps`` frames a second (``sigcore_viewer.browser.FRAME_CAP``), and still
runs every callback of a frame it draws; a frame rate that is not a positive number is refused before any browser
starts. In a real headless Chromium."""

from __future__ import annotations

import os
import time

import pytest
from sigcore_viewer.browser import Browser, missing

pytestmark = [pytest.mark.browser, pytest.mark.slow]

PAGE = "data:text/html,<html><body><p>frames</p></body></html>"
COUNT = """window.__a = 0; window.__b = 0; window.__same = 0;
(function a(t) { window.__a++; window.__ta = t; requestAnimationFrame(a); })();
(function b(t) { window.__b++; if (t === window.__ta) window.__same++; requestAnimationFrame(b); })();"""


@pytest.fixture(autouse=True)
def browser_ready() -> None:
    if os.environ.get("SIGCORE_NO_BROWSER"):
        pytest.skip("SIGCORE_NO_BROWSER is set: the viewer's browser tests are skipped")
    if missing() is not None:
        raise RuntimeError(f"the viewer's browser tests cannot run: {missing()}")


def _frames(page: Browser, seconds: float) -> tuple[float, float, int]:
    """Frames a second each of two animation loops saw over ``seconds``, and how many of the second loop's frames
    had the first's timestamp (ran in the same frame)."""
    page.driver.execute_script(COUNT)
    time.sleep(seconds)
    a, b, same = page.driver.execute_script("return [window.__a, window.__b, window.__same]")
    return a / seconds, b / seconds, int(same)


def test_a_capped_page_draws_at_most_its_frame_rate_and_runs_every_callback_of_a_frame() -> None:
    """At max_fps=5 two animation loops both run about 5 times a second (at most 6: the cap's 2 ms slack; at least
    3: Chromium may drop frames under load), in the same frames; uncapped, the same page draws far more often
    (at least 15 a second: Chromium's own pace here is 60 for a page this simple)."""
    with Browser(PAGE, max_fps=5) as page:
        a, b, same = _frames(page, 3.0)
        assert 3.0 <= a <= 6.0 and 3.0 <= b <= 6.0, (a, b)
        assert same >= 0.9 * b * 3.0 - 1, (same, b)
    with Browser(PAGE) as page:
        a, b, _ = _frames(page, 2.0)
        assert a >= 15.0 and b >= 15.0, (a, b)


@pytest.mark.parametrize("fps", [0, -1, float("nan"), float("inf")])
def test_a_frame_rate_that_is_not_a_positive_number_is_refused(fps: float) -> None:
    """max_fps 0, negative, NaN or infinite: ValueError naming what is valid, before a browser starts."""
    with pytest.raises(ValueError, match="max_fps must be a positive number"):
        Browser(PAGE, max_fps=fps)
