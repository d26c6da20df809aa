"""The one decorator that makes a formula's kernel: numba, compiled once and cached on disk.

A coupling term's kernel is plain Python on float arrays, so the same source reads as the
formula and runs compiled. The quaternion maths kernels share is :mod:`skills.quaternion`'s
scalar functions themselves, compiled here.

numba caches each kernel beside its source. Its cache checks only a kernel's own file, so
after editing a kernel that another file's kernel calls, delete the ``__pycache__/*.nbi``
and ``*.nbc`` files (a fresh checkout has none).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, TypeVar

import numba

from skills import quaternion as quat
from skills.types import Array

F = TypeVar("F", bound=Callable[..., Any])


def kernel(fn: F) -> F:
    """``fn`` compiled with numba (no Python objects, no GIL), its machine code cached on disk."""
    compiled: F = numba.njit(cache=True, nogil=True)(fn)  # type: ignore[assignment]
    return compiled


# skills.quaternion's scalar functions, compiled: every kernel shares their arithmetic.
rotation_error_q = kernel(quat.rotation_error_scalar)
matrix_q = kernel(quat.matrix_floats)
integrate_q = kernel(quat.integrate_scalar)
multiply_q = kernel(quat.multiply_scalar)


@kernel
def quaternion_at(x: Array, at: int) -> tuple[float, float, float, float]:
    """The quaternion at ``x[at:at + 4]`` as floats."""
    return (x[at], x[at + 1], x[at + 2], x[at + 3])
