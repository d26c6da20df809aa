"""What a run derives the same way every time, kept on disk under a name made of its inputs.

An entry is the output of a pure, deterministic computation, named by a digest of everything
that computation reads: its input files' bytes, the source of the code that computes it and
the versions of the libraries it calls (:func:`content_key`). A changed input is a different
name, so a stale entry is never found; an entry is never updated, only written once.

The folder is the user's own (``$XDG_CACHE_HOME/duet/<kind>``, else ``~/.cache/duet/<kind>``,
else a private temporary folder), refused if it is a link or another user's. An entry is
written to a temporary name and renamed into place, so parallel workers may race on it, and
each holds a SHA-256 of its payload that is checked on every read: a truncated, damaged or
planted file is computed again, never used.
"""

from __future__ import annotations

import hashlib
import importlib.metadata
import os
import stat
import tempfile
from collections.abc import Iterable
from functools import cache
from pathlib import Path

#: First line of every entry file: the layout of what follows (a digest line, the payload).
_MAGIC = b"duet-cache 1\n"
#: Largest entry read (a cached convex hull is a few kB, a skill library ~0.3 MB).
MAX_ENTRY_BYTES = 64 * 2**20


def default_cache_dir(kind: str) -> Path:
    """The user's cache folder for ``kind`` (e.g. ``"robots"``)."""
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "duet" / kind


def private_folder(folder: Path, what: str) -> Path:
    """``folder``, made if missing (mode 0700); refused if it is a link or another user's.

    Raises
    ------
    OSError
        Naming the folder and ``what`` it was for.
    """
    folder.mkdir(parents=True, exist_ok=True, mode=0o700)
    info = os.lstat(folder)
    if stat.S_ISLNK(info.st_mode) or not stat.S_ISDIR(info.st_mode):
        raise OSError(f"{folder}: expected a folder for {what}, got a link or a file")
    if hasattr(os, "getuid") and info.st_uid != os.getuid():
        raise OSError(f"{folder}: expected a folder of this user's for {what}")
    return folder


def cache_folder(kind: str, what: str, folder: Path | None = None) -> Path:
    """The private folder for ``kind``: ``folder`` if given, else the user's cache, else (no
    writable home: a container, a sandbox) a private temporary folder.

    Raises
    ------
    OSError
        If ``folder`` (or, by default, every candidate) is a link, another user's, or cannot
        be made.
    """
    if folder is not None:
        return private_folder(folder, what)
    try:
        return private_folder(default_cache_dir(kind), what)
    except OSError:
        uid = os.getuid() if hasattr(os, "getuid") else 0
        return private_folder(Path(tempfile.gettempdir()) / f"duet-{kind}-{uid}", what)


def content_key(parts: Iterable[bytes | str]) -> str:
    """A digest naming everything an entry is computed from (hex, 32 characters).

    Each part is length-prefixed, so ``("ab", "c")`` and ``("a", "bc")`` differ.
    """
    h = hashlib.sha256()
    for part in parts:
        data = part.encode() if isinstance(part, str) else part
        h.update(len(data).to_bytes(8, "little"))
        h.update(data)
    return h.hexdigest()[:32]


def versions(*distributions: str) -> list[str]:
    """``"name==version"`` of each installed distribution, for a key (``"name==absent"``)."""
    return [_version(name) for name in distributions]


@cache
def _version(name: str) -> str:
    # Once per process: reading a distribution's metadata takes milliseconds.
    try:
        return f"{name}=={importlib.metadata.version(name)}"
    except importlib.metadata.PackageNotFoundError:
        return f"{name}==absent"


def source_files(package: Path) -> list[bytes | str]:
    """Every ``.py`` file under ``package``: path relative to it and bytes, in sorted order."""
    parts: list[bytes | str] = []
    for path in sorted(package.rglob("*.py")):
        parts += [path.relative_to(package).as_posix(), path.read_bytes()]
    return parts


def read_entry(path: Path) -> bytes | None:
    """The payload of the entry at ``path``, or None when there is none that checks out (no
    file, a link, a folder, a truncated or damaged file, a digest that does not match)."""
    try:
        info = os.lstat(path)
        if not stat.S_ISREG(info.st_mode) or info.st_size > MAX_ENTRY_BYTES:
            return None
        data = path.read_bytes()
    except OSError:
        return None
    head = len(_MAGIC) + 65  # the magic line, then 64 hex digits and a newline
    if not data.startswith(_MAGIC) or len(data) < head or data[head - 1 : head] != b"\n":
        return None
    payload = data[head:]
    if hashlib.sha256(payload).hexdigest().encode() != data[len(_MAGIC) : head - 1]:
        return None
    return payload


def write_entry(path: Path, payload: bytes) -> None:
    """Write ``payload`` as the entry at ``path``: to a temporary name, then renamed into place
    (a reader sees the whole entry or none).

    Raises
    ------
    OSError
        If the folder cannot be written.
    """
    write_whole(path, _MAGIC + hashlib.sha256(payload).hexdigest().encode() + b"\n" + payload)


def write_whole(path: Path, data: bytes) -> None:
    """Write ``data`` to ``path`` through a temporary beside it, synced and renamed into place:
    a reader sees the whole file or none.

    Raises
    ------
    OSError
        If the folder cannot be written.
    """
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(data)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


__all__ = [
    "cache_folder",
    "content_key",
    "default_cache_dir",
    "private_folder",
    "read_entry",
    "source_files",
    "versions",
    "write_entry",
    "write_whole",
]
