"""The BLAS kernel pin (duet_robot.blas): asked for on x86-64 with AVX, never over a user's."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from duet_robot import blas


def fake_cpu(tmp_path: Path, flags: str) -> Path:
    path = tmp_path / "cpuinfo"
    path.write_text(f"processor\t: 0\nflags\t\t: fpu sse2 {flags}\n", encoding="utf-8")
    return path


def test_avx_is_read_from_the_flags_line(tmp_path: Path) -> None:
    assert blas._has_avx(fake_cpu(tmp_path, "avx avx2"))
    assert not blas._has_avx(fake_cpu(tmp_path, "avx2 avx512f"))  # whole words only
    assert not blas._has_avx(tmp_path / "missing")


def test_the_pin_is_set_on_x86_64_with_avx_and_never_over_a_users_choice(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    cpu = fake_cpu(tmp_path, "avx")
    read = blas._has_avx
    monkeypatch.setattr(blas, "_has_avx", lambda: read(cpu))
    monkeypatch.setattr(blas.platform, "machine", lambda: "x86_64")
    monkeypatch.delenv(blas.CORETYPE_VARIABLE, raising=False)
    assert blas.pin_blas_kernel() == blas.PINNED_CORE
    assert blas.os.environ[blas.CORETYPE_VARIABLE] == blas.PINNED_CORE
    monkeypatch.setenv(blas.CORETYPE_VARIABLE, "Haswell")
    assert blas.pin_blas_kernel() == "Haswell"
    monkeypatch.delenv(blas.CORETYPE_VARIABLE)
    monkeypatch.setattr(blas.platform, "machine", lambda: "aarch64")
    assert blas.pin_blas_kernel() is None
    assert blas.CORETYPE_VARIABLE not in blas.os.environ


CORE_NAME = """
import ctypes, glob, os
import numpy
libs = glob.glob(os.path.join(os.path.dirname(numpy.__file__) + ".libs", "libscipy_openblas*.so"))
if libs:
    lib = ctypes.CDLL(libs[0])
    lib.scipy_openblas_get_corename64_.restype = ctypes.c_char_p
    print(lib.scipy_openblas_get_corename64_().decode())
else:
    print("unknown")
"""


@pytest.mark.parametrize("first", ["app", "planner.testing.fixtures", "worlds.testing"])
def test_the_kernel_is_pinned_before_numpy_loads_it(first: str) -> None:
    # A fresh interpreter: importing app sets the variable, and OpenBLAS loads that kernel.
    # pytest imports its plugins before any conftest.py, so the two the package registers
    # pin it too: a suite run without xdist ran its trials on the CPU's own kernel (SkylakeX
    # here), and its in-process records differed from Ray's in the last digits.
    code = f"import os; os.environ.pop('OPENBLAS_CORETYPE', None); import {first}\n" + CORE_NAME
    code += "print(os.environ.get('OPENBLAS_CORETYPE'))\n"
    core, asked = subprocess.run(
        [sys.executable, "-c", code],
        capture_output=True,
        text=True,
        check=True,
        cwd=Path(__file__).resolve().parents[1],
    ).stdout.split()[-2:]
    if blas.platform.machine().lower() in ("x86_64", "amd64") and blas._has_avx():
        assert asked == blas.PINNED_CORE
    if asked == "None" or core == "unknown":
        pytest.skip(f"no kernel pinned here (asked {asked}, OpenBLAS core {core})")
    assert core.lower() == asked.lower()
