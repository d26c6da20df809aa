"""The compiled kernels' cache folder is named by every file that can hold a kernel."""

from __future__ import annotations

from pathlib import Path

import numba

from skills.kernel import PROJECT, kernel_cache_key


def test_an_edit_of_any_kernel_file_names_another_cache(tmp_path: Path) -> None:
    # numba's own cache checks a kernel's own file alone: the composition step, in
    # skills/interpreter.py, ran a coupling's kernel as compiled before its file was edited.
    for folder in ("skills/couplings", "worlds"):
        (tmp_path / folder).mkdir(parents=True)
    coupling = tmp_path / "skills" / "couplings" / "potential.py"
    coupling.write_text("SIGN = 1.0\n", encoding="utf-8")
    (tmp_path / "worlds" / "palm_ik.py").write_text("STEP = 0.5\n", encoding="utf-8")
    (tmp_path / "README.md").write_text("not code\n", encoding="utf-8")
    first = kernel_cache_key(tmp_path)
    (tmp_path / "README.md").write_text("still not code\n", encoding="utf-8")
    assert kernel_cache_key(tmp_path) == first
    coupling.write_text("SIGN = -1.0\n", encoding="utf-8")
    assert kernel_cache_key(tmp_path) != first
    coupling.write_text("SIGN = 1.0\n", encoding="utf-8")
    assert kernel_cache_key(tmp_path) == first
    (tmp_path / "worlds" / "palm_ik.py").write_text("STEP = 0.25\n", encoding="utf-8")
    assert kernel_cache_key(tmp_path) != first


def test_numba_caches_in_the_folder_of_this_source() -> None:
    cache = numba.config.CACHE_DIR
    assert not cache or Path(cache).name == kernel_cache_key(PROJECT)
