"""Client text in messages: quoted, bounded and made printable, so a hostile string cannot flood or forge a log.

Every refusal that names what a client sent (an unknown agent, a part, a service name, a filter) quotes it with
:func:`quote`; whatever writes a message into a log bounds the whole line with :func:`clip`.
"""

from __future__ import annotations

QUOTE_LIMIT = 80
"""At most this many characters of a client string are quoted [characters]."""

LINE_LIMIT = 400
"""At most this many characters of a refusal message go into a log line [characters]."""


def _printable(text: str) -> str:
    if text.isprintable():
        return text
    return "".join(c if c.isprintable() else repr(c)[1:-1] for c in text)


def quote(value: object, limit: int = QUOTE_LIMIT) -> str:
    """``'value'`` for a message: at most ``limit`` characters of it, control characters escaped.

    Args:
        value: What the client sent (converted with ``str``).
        limit: How many characters to keep [characters].

    Returns:
        ``'name'``, or ``'first characters…' (N characters)`` when longer than ``limit``.
    """
    text = str(value)
    if len(text) <= limit:
        return f"'{_printable(text)}'"
    return f"'{_printable(text[:limit])}…' ({len(text)} characters)"


def clip(message: str, limit: int = LINE_LIMIT) -> str:
    """``message`` cut to ``limit`` characters (plus how many were cut), control characters escaped.

    Args:
        message: A whole message, e.g. a refusal about to be logged.
        limit: How many characters to keep [characters].
    """
    if len(message) <= limit:
        return _printable(message)
    return f"{_printable(message[:limit])}… ({len(message) - limit} more characters)"
