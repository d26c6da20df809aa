"""One BLAS kernel on every x86-64 machine: a trial's outcome should not depend on the host.

numpy's matrix products go to OpenBLAS, which picks a kernel for the CPU it finds when it
loads: an AVX-512 machine and an AVX machine sum the same small products in different orders,
and the physics amplifies the last bit. Default world, trial 352 of seed 0 (slip in mm, peak
squeeze in N): SkylakeX kernel 51.975 and 69.19, Haswell 50.846 and 211.51, Sandybridge 51.939
and 86.43, the last what the campaign recorded on a machine whose OpenBLAS chose it.

:func:`pin_blas_kernel` asks OpenBLAS for its Sandybridge kernel (it needs AVX: asked for only
on a CPU that has it) unless ``OPENBLAS_CORETYPE`` is set already. OpenBLAS reads the variable once,
when numpy first loads it: call this before anything imports numpy. Standard library only.

It removes one source of host-dependent results, not every one: the Hard records made on that
other machine (with this kernel) still do not rerun bit for bit on an AVX-512 one.
"""

from __future__ import annotations

import os
import platform
from pathlib import Path

#: The kernel every record is computed with on x86-64 (OpenBLAS's name for it).
PINNED_CORE = "Sandybridge"
#: The environment variable OpenBLAS reads.
CORETYPE_VARIABLE = "OPENBLAS_CORETYPE"


def _has_avx(cpuinfo: Path = Path("/proc/cpuinfo")) -> bool:
    try:
        text = cpuinfo.read_text(encoding="utf-8", errors="replace")
    except OSError:
        return False
    for line in text.splitlines():
        if line.startswith("flags"):
            return "avx" in line.split(":", 1)[-1].split()
    return False


def pin_blas_kernel() -> str | None:
    """Set ``OPENBLAS_CORETYPE`` to :data:`PINNED_CORE` on an x86-64 Linux CPU with AVX, unless
    it is set; returns the kernel asked for (None: left to OpenBLAS)."""
    if CORETYPE_VARIABLE in os.environ:
        return os.environ[CORETYPE_VARIABLE] or None
    if platform.machine().lower() not in ("x86_64", "amd64") or not _has_avx():
        return None
    os.environ[CORETYPE_VARIABLE] = PINNED_CORE
    return PINNED_CORE
