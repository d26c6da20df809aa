"""Generated robot description files, cached by content in a folder of the user's own.

A cached file is trusted only if it holds exactly the text it is named after: a file planted
under its name (say, with palm friction 0) or one truncated by a crash is written again. The
folder is per user (``$XDG_CACHE_HOME/duet/robots``, else ``~/.cache/duet/robots``), made
private, and every file is written to a temporary name and renamed into place, so parallel
workers may race on it safely.
"""

from __future__ import annotations

import hashlib
import os
import stat
from pathlib import Path

from skills import file_cache

_WHAT = "cached robot files"


def default_cache_dir() -> Path:
    """The user's cache folder for generated robot files."""
    return file_cache.default_cache_dir("robots")


def _holds(path: Path, data: bytes) -> bool:
    """Whether ``path`` is a regular file (not a link) holding exactly ``data``."""
    try:
        info = os.lstat(path)
        if not stat.S_ISREG(info.st_mode) or info.st_size != len(data):
            return False
        with open(path, "rb") as fh:
            return fh.read(len(data) + 1) == data
    except OSError:
        return False


def cached_urdf(text: str, stem: str, cache_dir: Path | None = None) -> Path:
    """Write a generated URDF once per content and return its path.

    The file name carries a hash of ``text``, so a changed model gets a new file and an
    unchanged one is reused once its content is checked.

    Parameters
    ----------
    text : str
        URDF text.
    stem : str
        File name prefix (``kuka_iiwa_palm``, ``icub_trunk``, ...).
    cache_dir : Path, optional
        Default: :func:`default_cache_dir`.

    Raises
    ------
    OSError
        If the cache folder is a link, another user's, or cannot be written (for the default
        folder: neither the user's cache nor a private temporary folder).
    """
    data = text.encode()
    digest = hashlib.sha256(data).hexdigest()[:16]
    # By default the user's cache, else (no writable home) a private temporary folder.
    folder = file_cache.cache_folder("robots", _WHAT, cache_dir)
    path = folder / f"{stem}_{digest}.urdf"
    if not _holds(path, data):
        file_cache.write_whole(path, data)
    return path
