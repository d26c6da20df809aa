"""Text from files made safe to print on a terminal."""

from __future__ import annotations

import unicodedata


def printable(text: object) -> str:
    """``text`` safe to print on a terminal: control characters (newlines, ANSI escapes) are
    written as escapes, so a name from a file cannot print a line of its own."""
    return "".join(repr(ch)[1:-1] if unicodedata.category(ch)[0] == "C" else ch for ch in str(text))


__all__ = ["printable"]
