"""Client text in messages: quoted, bounded, printable (sigcore/text.py)."""

from __future__ import annotations

from sigcore.text import LINE_LIMIT, QUOTE_LIMIT, clip, quote


def test_quote_keeps_short_names_as_they_are() -> None:
    """A short printable name is quoted unchanged, so messages read as before."""
    assert quote("referee") == "'referee'" and quote("名前🤖") == "'名前🤖'" and quote("") == "''"


def test_quote_bounds_a_long_string_and_says_how_long_it_was() -> None:
    """A 100 kB string becomes its first QUOTE_LIMIT characters and its length."""
    text = quote("x" * 100_000)
    assert text == f"'{'x' * QUOTE_LIMIT}…' (100000 characters)"


def test_quote_and_clip_escape_control_characters() -> None:
    """A newline or escape sequence in client text cannot forge a log line or colour a terminal."""
    assert quote("bot\n[ERROR] forged") == "'bot\\n[ERROR] forged'"
    assert "\x1b" not in clip("a\x1b[31mred") and "\n" not in clip("a\nb")


def test_clip_bounds_a_whole_message() -> None:
    """A message longer than LINE_LIMIT is cut there, with the number of characters left out."""
    assert clip("short") == "short"
    out = clip("y" * (LINE_LIMIT + 50))
    assert out == "y" * LINE_LIMIT + "… (50 more characters)"
