"""Map lxml elements and attributes back to ``line:column`` in the source text.

lxml reports, for an element, the line where its start tag *ends* and no column. We re-scan the text: start
tags appear in document order, so the n-th start tag in the text (comments, CDATA and processing instructions
blanked out) is the n-th element of ``root.iter()``. Attributes are found by tokenising the start tag (so
``tags="mass=1"`` is not mistaken for ``mass``), and stray text by scanning between an element's children.
"""

from __future__ import annotations

import re

from lxml import etree

_BLANK = re.compile(r"<!--.*?-->|<!\[CDATA\[.*?\]\]>|<\?.*?\?>|<!DOCTYPE[^>]*>", re.S)
_START = re.compile(r"<([A-Za-z_][\w.\-:]*)")
_ATTRIBUTE = re.compile(r"""([^\s=/>]+)\s*=\s*(?:"[^"]*"|'[^']*')""")
_TEXT = re.compile(r"\S")


def _blank(match: re.Match[str]) -> str:
    """Blank a comment, PI or DOCTYPE; a CDATA section keeps one mark where it starts, since it is text."""
    blank = "".join(c if c == "\n" else " " for c in match.group(0))
    return "C" + blank[1:] if match.group(0).startswith("<![CDATA[") and match.group(0)[9:-3].strip() else blank


class SourceMap:
    """Locations of every element and attribute of one parsed XML document."""

    def __init__(self, text: str, root: etree._Element) -> None:
        self._text = _BLANK.sub(_blank, text)
        self._line_starts = [0] + [m.end() for m in re.finditer("\n", self._text)]
        starts = [m for m in _START.finditer(self._text)]
        elements = [e for e in root.iter() if isinstance(e.tag, str)]
        self._elements = elements  # keeps the lxml proxies alive, so id() stays valid
        self._offsets: dict[int, tuple[int, int]] = {}
        self._names: dict[int, int] = {}
        self._ends: dict[int, tuple[int, int]] = {}
        for element, match in zip(elements, starts, strict=False):
            self._offsets[id(element)] = (match.start(), self._tag_end(match.end()))
            self._names[id(element)] = match.end()

    def _tag_end(self, pos: int) -> int:
        quote = ""
        for i in range(pos, len(self._text)):
            c = self._text[i]
            if quote:
                if c == quote:
                    quote = ""
            elif c in "\"'":
                quote = c
            elif c == ">":
                return i
        return len(self._text)

    def _line_col(self, offset: int) -> tuple[int, int]:
        lo, hi = 0, len(self._line_starts) - 1
        while lo < hi:
            mid = (lo + hi + 1) // 2
            if self._line_starts[mid] <= offset:
                lo = mid
            else:
                hi = mid - 1
        return lo + 1, offset - self._line_starts[lo] + 1

    def element(self, element: etree._Element) -> tuple[int, int]:
        """``(line, column)`` of the ``<`` of ``element``'s start tag."""
        span = self._offsets.get(id(element))
        if span is None:
            return int(element.sourceline or 1), 1
        return self._line_col(span[0])

    def attribute(self, element: etree._Element, name: str) -> tuple[int, int]:
        """``(line, column)`` of attribute ``name`` in ``element``'s start tag (the element if absent)."""
        span = self._offsets.get(id(element))
        if span is None:
            return self.element(element)
        start = self._names[id(element)]
        for m in _ATTRIBUTE.finditer(self._text, start, span[1]):
            if m.group(1) == name:
                return self._line_col(m.start())
        return self._line_col(span[0])

    def _close(self, element: etree._Element) -> tuple[int, int] | None:
        """Offsets of ``element``'s end tag: its ``<`` and just past its ``>`` (both after a ``/>``)."""
        span = self._offsets.get(id(element))
        if span is None:
            return None
        if id(element) not in self._ends:
            if self._text[span[1] - 1] == "/":
                self._ends[id(element)] = (span[1] + 1, span[1] + 1)
            else:
                children = [c for c in element if isinstance(c.tag, str)]
                last = self._close(children[-1]) if children else None
                close = self._text.find("</", last[1] if last is not None else span[1] + 1)
                if close < 0:
                    close = len(self._text)
                end = self._text.find(">", close)
                self._ends[id(element)] = (close, end + 1 if end >= 0 else len(self._text))
        return self._ends[id(element)]

    def text(self, element: etree._Element) -> tuple[int, int]:
        """``(line, column)`` of the first non-blank text directly in ``element`` (the element if none)."""
        span, close = self._offsets.get(id(element)), self._close(element)
        if span is None or close is None:
            return self.element(element)
        pos = span[1] + 1
        for child in [c for c in element if isinstance(c.tag, str)]:
            child_span, child_close = self._offsets.get(id(child)), self._close(child)
            if child_span is None or child_close is None:
                return self.element(element)
            m = _TEXT.search(self._text, pos, child_span[0])
            if m is not None:
                return self._line_col(m.start())
            pos = child_close[1]
        m = _TEXT.search(self._text, pos, close[0])
        return self._line_col(m.start()) if m is not None else self.element(element)
