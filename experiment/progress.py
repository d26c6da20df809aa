"""A campaign's progress, as suits where it is written: in place on a terminal, otherwise a
line every few percent (a CI log gets no carriage returns)."""

from __future__ import annotations

from typing import TextIO


class Progress:
    """Report trials as they finish.

    Parameters
    ----------
    stream : text stream
        Where to write (a terminal updates in place: ``stream.isatty()``).
    step_percent : float
        Off a terminal, a line each time this much more of the campaign has finished.
    width : int
        Characters of the bar.
    """

    def __init__(self, stream: TextIO, step_percent: float = 5.0, width: int = 30) -> None:
        if not 0.0 < step_percent <= 100.0:
            raise ValueError(f"Progress: expected step_percent in (0, 100], got {step_percent}")
        isatty = getattr(stream, "isatty", None)
        self._stream = stream
        self._tty = bool(isatty()) if callable(isatty) else False
        self._step = step_percent
        self._width = width
        self._next = step_percent
        self._open = False

    def update(self, finished: int, total: int, text: str) -> None:
        """``finished`` of ``total`` trials done; ``text`` says what the last one did."""
        if self._tty:
            filled = int(self._width * finished / max(total, 1))
            bar = "#" * filled + "." * (self._width - filled)
            self._stream.write(f"\r[{bar}] {finished}/{total}  {text}".ljust(100))
            self._open = True
        else:
            percent = 100.0 * finished / max(total, 1)
            if percent + 1e-9 < self._next and finished < total:
                return
            while self._next <= percent + 1e-9:
                self._next += self._step
            self._stream.write(f"{finished}/{total} ({percent:.0f} %)  {text}\n")
        self._stream.flush()

    def close(self) -> None:
        """End the line a terminal's bar was on."""
        if self._open:
            self._stream.write("\n")
            self._stream.flush()
            self._open = False
