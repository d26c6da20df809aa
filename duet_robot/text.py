"""Text from files made safe to print on a terminal."""

from __future__ import annotations

import unicodedata


def printable(text: object) -> str:
    """``text`` safe to print on a terminal: control characters (newlines, ANSI escapes) are
    written as escapes, so a name from a file cannot print a line of its own."""
    return "".join(repr(ch)[1:-1] if unicodedata.category(ch)[0] == "C" else ch for ch in str(text))


def with_notes(err: BaseException) -> str:
    """An error's message, then each note added to it (``add_note``), one a line: what the
    command line prints of an error it stops on."""
    return "\n".join([str(err), *getattr(err, "__notes__", ())])


__all__ = ["printable", "with_notes"]
