"""A campaign's results file: read it whatever state a crash left it in, append to it safely.

``results.jsonl`` holds one JSON record per finished trial, appended as trials finish, so a
campaign resumes where it stopped. What a kill, a full disk or a careless edit can leave:

* a torn last line (a kill mid-write): :func:`repair_tail` cuts it before anything is
  appended, so the next record starts on a line of its own, and keeps it beside the file; a
  whole record without its newline gets one;
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
        ``success``, and every field the summaries read of the type they read.
    skipped : int
        Lines that were not records (not UTF-8, not JSON, or fields of the wrong type).
    problems : tuple of str
        Why, for the first of them: ``line 7: field 'failure': expected a string, got 5``.
    """

    records: list[dict[str, Any]]
    skipped: int
    problems: tuple[str, ...] = ()

    def skipped_text(self, most: int = 3) -> str:
        """The skipped lines' count and the first reasons, for a warning."""
        shown = "; ".join(self.problems[:most])
        more = f"; {self.skipped - most} more" if self.skipped > most else ""
        return f"skipped {self.skipped} line(s) that are not trial records ({shown}{more})"


def _is_int(value: object) -> bool:
    return isinstance(value, int) and not isinstance(value, bool)


def _is_number(value: object) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool)


def _numbers(value: object, least: int = 0) -> bool:
    return isinstance(value, list) and len(value) >= least and all(map(_is_number, value))


def _counts(value: object) -> bool:
    return isinstance(value, dict) and all(_is_number(v) for v in value.values())


#: What the summaries, the report and its picture read of a record, by field: a check and
#: what it expects. A field a record lacks is not checked (older records lack some).
FIELD_TYPES: dict[str, tuple[Any, str]] = {
    **{
        name: (lambda v: isinstance(v, str), "a string")
        for name in ("failure", "reason", "tree_status", "mode", "world", "backend", "host")
    },
    **{
        name: (lambda v: v is None or _is_number(v), "a number or null")
        for name in (
            "sim_time_s",
            "wall_time_s",
            "physics_wall_s",
            "control_wall_s",
            "watch_wall_s",
            "min_obstacle_distance_m",
            "min_forearm_distance_m",
            "slip_mm",
            "peak_tilt_deg",
            "palm_velocity_mismatch_mps",
            "peak_jerk_mps3",
            "peak_squeeze_n",
            "arm_contacts",
            "contact_count",
            "regrasp_count",
        )
    },
    **{
        name: (
            lambda v: isinstance(v, list) and all(x is None or _is_number(x) for x in v),
            "a list of numbers or nulls",
        )
        for name in ("placement_error_m", "placement_error_deg")
    },
    **{
        name: (_counts, "a mapping of names to counts")
        for name in ("obstacle_contacts", "forearm_contacts", "table_contacts")
    },
    "dropped": (lambda v: isinstance(v, bool), "true or false"),
    "start": (lambda v: _numbers(v, 2), "a list of at least 2 numbers"),
    "goals": (
        lambda v: isinstance(v, list) and all(_numbers(g, 2) for g in v),
        "a list of lists of at least 2 numbers",
    ),
    "obstacles": (lambda v: isinstance(v, list), "a list"),
    "compositions": (
        lambda v: (
            isinstance(v, list)
            and all(
                c is None
                or (isinstance(c, dict) and all(x is None or _is_number(x) for x in c.values()))
                for c in v
            )
        ),
        "a list of mappings of names to numbers (or nulls)",
    ),
}


def _record(line: bytes) -> dict[str, Any] | None:
    """The record on one line, or None when the line is not one."""
    return _read_record(line)[0]


def _read_record(line: bytes) -> tuple[dict[str, Any] | None, str]:
    """The record on one line, or None and why it is not one."""
    try:
        rec = json.loads(line.decode("utf-8"))
    except UnicodeDecodeError:
        return None, "not UTF-8 text"
    except (json.JSONDecodeError, RecursionError):
        return None, "not JSON"
    if not isinstance(rec, dict):
        return None, f"expected a JSON object, got {type(rec).__name__}"
    for name, ok, expected in (
        ("trial", lambda v: _is_int(v) and v >= 0, "a whole number >= 0"),
        ("seed", _is_int, "a whole number"),
        ("success", lambda v: isinstance(v, bool), "true or false"),
    ):
        if not ok(rec.get(name)):
            return None, f"field '{name}': expected {expected}, got {_shown(rec.get(name))}"
    if not isinstance(rec.get("tree", ""), str):
        return None, f"field 'tree': expected a string, got {_shown(rec['tree'])}"
    for name, (check, expected) in FIELD_TYPES.items():
        if name in rec and not check(rec[name]):
            return None, f"field '{name}': expected {expected}, got {_shown(rec[name])}"
    return rec, ""


def _shown(value: object) -> str:
    text = json.dumps(value)
    return text if len(text) <= 40 else text[:37] + "..."


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
    records, problems = [], []
    for number, line in enumerate(data.splitlines(), 1):
        if not line.strip():
            continue
        rec, why = _read_record(line)
        if rec is None:
            problems.append(f"line {number}: {why}")
        else:
            records.append(rec)
    return Results(records, len(problems), tuple(problems))


def repair_tail(path: Path) -> int:
    """Make ``path`` end on a whole line before anything is appended; the bytes cut.

    A last line without its newline that is a whole record (a file another tool wrote, or
    two joined with ``cat``) gets its newline and stays. One that is not (a kill mid-write)
    is cut off and kept beside the file, in ``results.jsonl.torn``, so nothing is lost. A
    file that already ends a line is only read.

    Raises
    ------
    ResultsFileError
        As :func:`read_results`, or if the file must be changed and cannot be written.
    """
    _check_file(path)
    if not path.exists():
        return 0
    try:
        with open(path, "rb") as fh:
            size = fh.seek(0, os.SEEK_END)
            if size == 0:
                return 0
            fh.seek(size - 1)
            if fh.read(1) == b"\n":
                return 0
            keep = _last_line_start(fh, size)
            fh.seek(keep)
            tail = fh.read()
    except OSError as err:
        raise ResultsFileError(f"{path}: cannot read it: {err.strerror or err}") from None
    try:
        with open(path, "rb+") as fh:
            if _record(tail) is not None:
                fh.seek(size)
                fh.write(b"\n")
                cut = 0
            else:
                with open(path.with_name(path.name + ".torn"), "ab") as aside:
                    aside.write(tail + b"\n")
                fh.truncate(keep)
                cut = size - keep
            fh.flush()
            os.fsync(fh.fileno())
            return cut
    except OSError as err:
        raise ResultsFileError(f"{path}: cannot repair it: {err.strerror or err}") from None


def _last_line_start(fh: Any, size: int) -> int:
    """Where the last line of the open file ``fh`` of ``size`` bytes starts."""
    step = 1 << 16
    end = size
    while end > 0:
        start = max(0, end - step)
        fh.seek(start)
        at = fh.read(end - start).rfind(b"\n")
        if at >= 0:
            return start + at + 1
        end = start
    return 0


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
