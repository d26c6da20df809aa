"""The one decorator that makes a formula's kernel: numba, compiled once and cached on disk.

A coupling term's kernel is plain Python on float arrays, so the same source reads as the
formula and runs compiled. The quaternion maths kernels share is :mod:`skills.quaternion`'s
scalar functions themselves, compiled here.

numba caches each kernel's machine code, but its cache checks only the kernel's own file: a
kernel that calls another file's kernel (the composition step calls every coupling's) is
loaded as compiled before that file was edited. So the cache lives in a folder named by the
source of every file that can hold a kernel (``skills`` and ``worlds``) and numba's and
numpy's versions (:func:`kernel_cache_key`), under the user's cache
(``~/.cache/duet/kernels/<key>``): an update, or an edit of any kernel, compiles afresh, once.
``NUMBA_CACHE_DIR``, when set, is used as it is.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path
from typing import Any, TypeVar

import numba

from skills import file_cache
from skills import quaternion as quat
from skills.types import Array

#: The project's folder; kernels live in its ``skills`` and ``worlds``.
PROJECT = Path(__file__).resolve().parents[1]


def kernel_cache_key(project: Path = PROJECT) -> str:
    """The name of the compiled kernels' cache folder: a digest of every ``.py`` file under
    ``project``'s ``skills`` and ``worlds`` and of numba's and numpy's versions."""
    parts = [
        *file_cache.source_files(project / "skills"),
        *file_cache.source_files(project / "worlds"),
        *file_cache.versions("numba", "numpy"),
    ]
    return file_cache.content_key(parts)


def _use_kernel_cache() -> None:
    """Point numba's cache at this source's folder (module docstring); where none can be
    made, numba's own, beside the sources."""
    if os.environ.get("NUMBA_CACHE_DIR"):
        return
    try:
        folder = file_cache.cache_folder("kernels", "compiled kernels") / kernel_cache_key()
        file_cache.private_folder(folder, "compiled kernels")
    except OSError:
        return
    numba.config.CACHE_DIR = str(folder)  # type: ignore[attr-defined]


_use_kernel_cache()

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
