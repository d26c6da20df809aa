"""A context manager for anything with a ``close()``: the one ``__enter__`` and ``__exit__``."""

from __future__ import annotations

from typing import Self


class Closing:
    """Mixin: ``with Thing(...) as thing:`` gives the thing itself and closes it on the way
    out, whatever ends the block. Subclasses define :meth:`close` (idempotent)."""

    def close(self) -> None:
        """Release what the object holds."""
        raise NotImplementedError(f"{type(self).__name__}.close")

    def __enter__(self) -> Self:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


__all__ = ["Closing"]
