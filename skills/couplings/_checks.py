"""Validators shared by the coupling terms: coerce, and say what was expected and received."""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

from skills.types import Array

ZERO3: Array = np.zeros(3)
ZERO3.setflags(write=False)


def positive(value: float, name: str) -> float:
    """``value`` as a float, or ValueError naming ``name`` unless finite and > 0."""
    v = float(value)
    if not (math.isfinite(v) and v > 0.0):
        raise ValueError(f"{name}: expected a finite number > 0, got {value!r}")
    return v


def non_negative(value: float, name: str) -> float:
    """``value`` as a float, or ValueError naming ``name`` unless finite and >= 0."""
    v = float(value)
    if not (math.isfinite(v) and v >= 0.0):
        raise ValueError(f"{name}: expected a finite number >= 0, got {value!r}")
    return v


def vector(value: ArrayLike, shape: tuple[int, ...], name: str) -> Array:
    """A finite, read-only float array of ``shape`` (use -1 for any length)."""
    arr = np.array(value, dtype=float)
    ok = arr.ndim == len(shape) and all(s in (-1, n) for s, n in zip(shape, arr.shape, strict=True))
    if not ok:
        want = "(" + ", ".join("N" if s == -1 else str(s) for s in shape) + ")"
        raise ValueError(f"{name}: expected shape {want}, got {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name}: expected finite values, got NaN or inf")
    arr.setflags(write=False)
    return arr


def unit_vector(value: ArrayLike, name: str) -> Array:
    """A read-only unit 3-vector, or ValueError on a zero or non-finite one."""
    arr = np.array(vector(value, (3,), name))
    n = float(np.linalg.norm(arr))
    if n < 1e-9:
        raise ValueError(f"{name}: expected a non-zero direction, got {value!r}")
    arr /= n
    arr.setflags(write=False)
    return arr


def assign(obj: object, **values: object) -> None:
    """Set attributes on a frozen dataclass from its hand-written ``__init__``.

    The coupling classes take ``array_like`` arguments but hold validated arrays, so each
    writes its ``__init__`` (typed for callers) and validates in ``__post_init__``.
    """
    for name, value in values.items():
        object.__setattr__(obj, name, value)
