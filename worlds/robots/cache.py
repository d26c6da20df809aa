"""Generated robot description files, cached by content."""

from __future__ import annotations

import hashlib
import os
import tempfile
from pathlib import Path


def cached_urdf(text: str, stem: str, cache_dir: Path | None = None) -> Path:
    """Write a generated URDF once per content and return its path.

    The file name carries a hash of ``text``, so a changed model gets a new file and an
    unchanged one is reused. It is written to a temporary file and renamed into place:
    parallel workers may race on the same file.

    Parameters
    ----------
    text : str
        URDF text.
    stem : str
        File name prefix (``kuka_iiwa_palm``, ``icub_trunk``, ...).
    cache_dir : Path, optional
        Default: ``duet_robots`` in the system's temporary folder.
    """
    digest = hashlib.sha1(text.encode()).hexdigest()[:12]
    folder = cache_dir if cache_dir is not None else Path(tempfile.gettempdir()) / "duet_robots"
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / f"{stem}_{digest}.urdf"
    if not path.exists():
        fd, tmp = tempfile.mkstemp(dir=folder, suffix=".urdf")
        with os.fdopen(fd, "w") as f:
            f.write(text)
        os.replace(tmp, path)
    return path
