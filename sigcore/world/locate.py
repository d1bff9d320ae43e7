"""Map lxml elements and attributes back to ``line:column`` in the source text.

lxml reports, for an element, the line where its start tag *ends* and no column. We re-scan the text: start tags
appear in document order, so the n-th start tag in the text (comments, CDATA and processing instructions blanked
out) is the n-th element of ``root.iter()``.
"""

from __future__ import annotations

import re

from lxml import etree

_BLANK = re.compile(r"<!--.*?-->|<!\[CDATA\[.*?\]\]>|<\?.*?\?>|<!DOCTYPE[^>]*>", re.S)
_START = re.compile(r"<([A-Za-z_][\w.\-:]*)")


def _blank(match: re.Match[str]) -> str:
    return "".join(c if c == "\n" else " " for c in match.group(0))


class SourceMap:
    """Locations of every element and attribute of one parsed XML document."""

    def __init__(self, text: str, root: etree._Element) -> None:
        self._text = _BLANK.sub(_blank, text)
        self._line_starts = [0] + [m.end() for m in re.finditer("\n", self._text)]
        starts = [m for m in _START.finditer(self._text)]
        elements = [e for e in root.iter() if isinstance(e.tag, str)]
        self._elements = elements  # keeps the lxml proxies alive, so id() stays valid
        self._offsets: dict[int, tuple[int, int]] = {}
        for element, match in zip(elements, starts, strict=False):
            self._offsets[id(element)] = (match.start(), self._tag_end(match.end()))

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
        tag = self._text[span[0] : span[1]]
        m = re.search(r"(?<![\w.\-:])" + re.escape(name) + r"\s*=", tag)
        if m is None:
            return self._line_col(span[0])
        return self._line_col(span[0] + m.start())
