"""Write a file whole or not at all: through a temporary file beside it, renamed into place.

A run killed while writing ``run.jsonl`` or a figure, or a disk that fills up halfway, must
never leave half a file under the final name, where the next reader takes it for whole. Each
writer here writes a hidden temporary in the same folder (so the rename is atomic, never a
copy across file systems) and renames it over the final name only once it is complete; on
an error the temporary is removed and the final name keeps what it had. A process killed
outright leaves only the hidden temporary (``.<name>.<random>.part<suffix>``), which
:func:`stale_temporaries` finds for the next run to remove.
"""

from __future__ import annotations

import os
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import IO, Any

#: Infix of every temporary's name: ``.run.jsonl.x8k2.part.jsonl``.
PART = ".part"


def temporary_beside(path: Path) -> Path:
    """A new empty hidden file beside ``path``, keeping its suffix (writers that choose the
    format by suffix, such as matplotlib's ``savefig``, still see it)."""
    fd, name = tempfile.mkstemp(
        dir=path.parent, prefix=f".{path.name}.", suffix=f"{PART}{path.suffix}"
    )
    # mkstemp makes it 0600; the file it becomes gets a new file's mode under the umask, as
    # open() would have given it (run.jsonl and the figures had been unreadable to the group).
    os.fchmod(fd, 0o666 & ~_umask())
    os.close(fd)
    return Path(name)


def _umask() -> int:
    """The process's umask: from ``/proc/self/status`` where Linux gives it (reading it by
    setting it would leave it 0 for a moment to another thread), else set and set back."""
    try:
        with open("/proc/self/status", encoding="ascii") as status:
            for line in status:
                if line.startswith("Umask:"):
                    return int(line.split()[1], 8)
    except (OSError, ValueError):
        pass
    mask = os.umask(0)
    os.umask(mask)
    return mask


def commit(temporary: Path, path: Path) -> None:
    """Rename a finished ``temporary`` over ``path`` (atomic on one file system)."""
    os.replace(temporary, path)


@contextmanager
def atomic_path(path: str | os.PathLike[str]) -> Iterator[Path]:
    """A temporary path to write ``path`` through; renamed over ``path`` when the block ends
    without an error, removed when it raises."""
    target = Path(path)
    temporary = temporary_beside(target)
    try:
        yield temporary
        commit(temporary, target)
    except BaseException:
        temporary.unlink(missing_ok=True)
        raise


@contextmanager
def atomic_open(
    path: str | os.PathLike[str], mode: str = "w", encoding: str | None = "utf-8"
) -> Iterator[IO[Any]]:
    """Open ``path`` for writing through a temporary (see :func:`atomic_path`); the data is
    flushed to disk before the rename."""
    with atomic_path(path) as temporary:
        with open(temporary, mode, encoding=None if "b" in mode else encoding) as handle:
            yield handle
            handle.flush()
            os.fsync(handle.fileno())


def stale_temporaries(folder: Path, name: str) -> list[Path]:
    """Temporaries of ``name`` a killed writer left in ``folder`` (regular files only)."""
    pattern = f".{name}.*{PART}{Path(name).suffix}"
    return sorted(p for p in folder.glob(pattern) if p.is_file() and not p.is_symlink())


__all__ = ["atomic_open", "atomic_path", "commit", "stale_temporaries", "temporary_beside"]
