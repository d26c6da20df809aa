"""Demonstration CSV files: a header, then one row per sample.

Columns ``t, x, y, z, qx, qy, qz, qw`` (s, m, scalar-last quaternion) come first; a skill may
need more (an obstacle's ``ox, oy, oz, radius``, a contact force ``force``), which follow.
Errors name the file, the row or column and what was expected.
"""

from __future__ import annotations

import csv
import math
import os
import tempfile
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike

from skills.demonstration import Demonstration
from skills.types import Array

POSE_COLUMNS: tuple[str, ...] = ("t", "x", "y", "z", "qx", "qy", "qz", "qw")


class DemoFileError(ValueError):
    """A demonstration file that cannot be used; the message names file, place and problem."""


@dataclass(frozen=True)
class DemoFile:
    """A demonstration read from CSV.

    Attributes
    ----------
    demonstration : Demonstration
        Time, positions (N, 3) and orientations (N, 4), validated.
    extra : Mapping[str, ndarray]
        Further columns by name, each (N,).
    path : Path
    """

    demonstration: Demonstration
    extra: Mapping[str, Array]
    path: Path


def read_demo_csv(path: str | os.PathLike[str]) -> DemoFile:
    """Read and validate a demonstration CSV.

    Raises
    ------
    DemoFileError
        Missing file, missing or duplicate columns, a non-numeric cell (with its row and
        column), too few rows, or anything :meth:`Demonstration.create` rejects.
    """
    p = Path(path)
    label = str(path)
    try:
        # utf-8-sig: a spreadsheet's byte order mark is not part of the first column's name.
        text = p.read_text(encoding="utf-8-sig")
    except FileNotFoundError:
        raise DemoFileError(
            f"{label}: expected a demonstration CSV file, got no such file"
        ) from None
    except (OSError, UnicodeDecodeError) as err:
        raise DemoFileError(f"{label}: expected a readable UTF-8 CSV file, got {err}") from None
    rows = list(csv.reader(line for line in text.splitlines() if line.strip()))
    if not rows:
        raise DemoFileError(
            f"{label}: expected a header {','.join(POSE_COLUMNS)}, got an empty file"
        )
    header = [h.strip() for h in rows[0]]
    missing = [c for c in POSE_COLUMNS if c not in header]
    if missing:
        raise DemoFileError(
            f"{label}: header: expected columns {', '.join(POSE_COLUMNS)}, "
            f"missing {', '.join(missing)}"
        )
    dupes = sorted({h for h in header if header.count(h) > 1})
    if dupes:
        raise DemoFileError(
            f"{label}: header: expected unique column names, got {', '.join(dupes)} twice"
        )
    data = np.empty((len(rows) - 1, len(header)))
    for i, row in enumerate(rows[1:], start=2):  # file line numbers; rows are few thousand
        if len(row) != len(header):
            raise DemoFileError(
                f"{label}:{i}: expected {len(header)} values like the header, got {len(row)}"
            )
        for j, cell in enumerate(row):
            try:
                data[i - 2, j] = float(cell)
            except ValueError:
                raise DemoFileError(
                    f"{label}:{i}: column {header[j]}: expected a number, got {cell.strip()!r}"
                ) from None
    col = {h: data[:, k] for k, h in enumerate(header)}
    try:
        demo = Demonstration.create(
            col["t"],
            np.stack([col["x"], col["y"], col["z"]], axis=1),
            np.stack([col["qx"], col["qy"], col["qz"], col["qw"]], axis=1),
            name=label,
        )
    except ValueError as err:
        raise DemoFileError(str(err)) from None
    extra = {h: v for h, v in col.items() if h not in POSE_COLUMNS}
    return DemoFile(demo, extra, p)


def write_demo_csv(
    path: str | os.PathLike[str],
    t: ArrayLike,
    positions: ArrayLike,
    orientations: ArrayLike,
    extra: Mapping[str, ArrayLike] | None = None,
) -> Path:
    """Write a demonstration CSV atomically (a temporary file renamed into place).

    Parameters
    ----------
    path : path-like
    t : array_like, shape (N,)
    positions : array_like, shape (N, 3)
    orientations : array_like, shape (N, 4)
    extra : mapping of str to array_like (N,), optional
        Further columns, written after the pose columns in the given order.
    """
    demo = Demonstration.create(t, positions, orientations, name=str(path))
    assert demo.orientations is not None
    names: list[str] = list(POSE_COLUMNS)
    cols: list[Array] = [demo.t, *demo.positions.T, *demo.orientations.T]
    for name, values in (extra or {}).items():
        arr = np.asarray(values, dtype=float)
        if arr.shape != demo.t.shape:
            raise ValueError(f"extra[{name!r}]: expected shape {demo.t.shape}, got {arr.shape}")
        names.append(name)
        cols.append(arr)
    table = np.stack(cols, axis=1)
    out = Path(path)
    out.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=out.parent, prefix=f".{out.name}.", suffix=".tmp")
    with os.fdopen(fd, "w", encoding="utf-8", newline="") as fh:
        fh.write(",".join(names) + "\n")
        fh.writelines(",".join(_fmt(v) for v in row) + "\n" for row in table.tolist())
    os.chmod(tmp, 0o644)  # mkstemp makes it private; demonstrations are meant to be read
    os.replace(tmp, out)
    return out


def _fmt(v: float) -> str:
    if not math.isfinite(v):
        raise ValueError(f"expected finite values to write, got {v}")
    return f"{v:.9g}"


def columns(demo_file: DemoFile, names: Sequence[str]) -> Array:
    """Extra columns stacked as (N, len(names)); errors name the file and the missing column."""
    missing = [n for n in names if n not in demo_file.extra]
    if missing:
        raise DemoFileError(
            f"{demo_file.path}: header: expected columns {', '.join(names)} for this skill, "
            f"missing {', '.join(missing)}"
        )
    return np.stack([demo_file.extra[n] for n in names], axis=1)
