"""How fast the tests' headless browsers draw.

Chromium draws WebGL in software here and takes about 1.4 of the machine's 2 CPUs while a viewer page is open,
whatever the window's size (about 17 frames a second); the suite runs several such tests beside each other. The
tests read the page's text and take screenshots; they need the page drawn, not drawn often: at :data:`PAGE_FPS`
Chromium takes about half of one CPU. The benches that measure the page (``bench/viewer_overhead.py``,
``bench/viewer_first_paint.py``) draw as fast as Chromium can.
"""

PAGE_FPS = 5.0
"""Animation frames a second a test's page draws at most (``Browser(url, max_fps=PAGE_FPS)``)."""
