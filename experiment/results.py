"""A campaign's results file: read it whatever state a crash left it in, append to it safely.

``results.jsonl`` holds one JSON record per finished trial, appended as trials finish, so a
campaign resumes where it stopped. What a kill, a full disk or a careless edit can leave:

* a torn last line (a kill mid-write): :func:`repair_tail` cuts it before anything is
  appended, so the next record starts on a line of its own;
* lines that are not records (bytes that are not UTF-8, not JSON, a record whose fields have
  the wrong types): :func:`read_results` skips them and counts them, so that the caller can
  warn; those trials are run again;
* the path being a folder or unreadable: :class:`ResultsFileError`, one line, never a
  traceback;
* two campaigns writing into one folder: :func:`campaign_lock` takes an exclusive lock on
  the folder for the whole campaign; the second one is refused with
  :class:`CampaignBusyError`, naming the process that holds it.
"""

from __future__ import annotations

import errno
import fcntl
import json
import os
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any

#: The lock file a campaign holds in its folder.
LOCK_NAME = ".campaign.lock"


class ResultsFileError(Exception):
    """The results file cannot be read or written; the message names it and why."""


class CampaignBusyError(ResultsFileError):
    """Another campaign holds the folder's lock."""


@dataclass(frozen=True)
class Results:
    """The readable records of a results file and how many lines were not.

    Attributes
    ----------
    records : list of dict
        In file order; each has an integer ``trial``, an integer ``seed`` and a bool
        ``success``.
    skipped : int
        Lines that were not records (not UTF-8, not JSON, or fields of the wrong type).
    """

    records: list[dict[str, Any]]
    skipped: int


def _is_int(value: object) -> bool:
    return isinstance(value, int) and not isinstance(value, bool)


def _record(line: bytes) -> dict[str, Any] | None:
    """The record on one line, or None when the line is not one."""
    try:
        rec = json.loads(line.decode("utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError, RecursionError):
        return None
    if not isinstance(rec, dict):
        return None
    if not (_is_int(rec.get("trial")) and rec["trial"] >= 0 and _is_int(rec.get("seed"))):
        return None
    if not isinstance(rec.get("success"), bool) or not isinstance(rec.get("tree", ""), str):
        return None
    return rec


def _check_file(path: Path) -> None:
    if path.is_dir():
        raise ResultsFileError(f"{path}: expected a results file, got a folder")
    if path.exists() and not path.is_file():
        raise ResultsFileError(f"{path}: expected a regular file")


def read_results(path: Path) -> Results:
    """Every record in ``path`` (none if it does not exist), and how many lines were not.

    Raises
    ------
    ResultsFileError
        If ``path`` is a folder, not a regular file, or cannot be read.
    """
    _check_file(path)
    if not path.exists():
        return Results([], 0)
    try:
        data = path.read_bytes()
    except OSError as err:
        raise ResultsFileError(f"{path}: cannot read it: {err.strerror or err}") from None
    records, skipped = [], 0
    for line in data.splitlines():
        if not line.strip():
            continue
        rec = _record(line)
        if rec is None:
            skipped += 1
        else:
            records.append(rec)
    return Results(records, skipped)


def repair_tail(path: Path) -> int:
    """Cut a torn last line (one without its newline) off ``path``; the bytes cut.

    Raises
    ------
    ResultsFileError
        As :func:`read_results`, or if the file cannot be written.
    """
    _check_file(path)
    if not path.exists():
        return 0
    try:
        with open(path, "rb+") as fh:
            size = fh.seek(0, os.SEEK_END)
            if size == 0:
                return 0
            fh.seek(size - 1)
            if fh.read(1) == b"\n":
                return 0
            # Find the last newline: everything after it is the torn record.
            keep, step = 0, 1 << 16
            end = size
            while end > 0:
                start = max(0, end - step)
                fh.seek(start)
                at = fh.read(end - start).rfind(b"\n")
                if at >= 0:
                    keep = start + at + 1
                    break
                end = start
            fh.truncate(keep)
            fh.flush()
            os.fsync(fh.fileno())
            return size - keep
    except OSError as err:
        raise ResultsFileError(f"{path}: cannot repair it: {err.strerror or err}") from None


@contextmanager
def campaign_lock(folder: Path) -> Iterator[None]:
    """Hold ``folder``'s campaign lock while the block runs (released however it ends,
    and by the system if the process dies).

    Raises
    ------
    CampaignBusyError
        If another process holds it.
    ResultsFileError
        If the lock file cannot be made.
    """
    lock = folder / LOCK_NAME
    try:
        fd = os.open(lock, os.O_RDWR | os.O_CREAT | getattr(os, "O_NOFOLLOW", 0), 0o644)
    except OSError as err:
        raise ResultsFileError(f"{lock}: cannot take the lock: {err.strerror or err}") from None
    try:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError as err:
            if err.errno not in (errno.EWOULDBLOCK, errno.EAGAIN, errno.EACCES):
                raise ResultsFileError(f"{lock}: cannot take the lock: {err}") from None
            holder = os.pread(fd, 32, 0).decode("ascii", "replace").strip() or "unknown"
            raise CampaignBusyError(
                f"{folder}: another campaign (process {holder}) is writing its results "
                "here; wait for it to finish or choose another --out"
            ) from None
        os.ftruncate(fd, 0)
        os.pwrite(fd, str(os.getpid()).encode("ascii"), 0)
        yield
    finally:
        os.close(fd)  # closing releases the lock
