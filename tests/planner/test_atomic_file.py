"""Files written whole or not at all (issue 15, items 12 and 13)."""

from __future__ import annotations

import errno
import os
import stat
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import app
from planner.atomic_file import atomic_open, atomic_path, stale_temporaries
from planner.runlog import RunLog


def test_a_write_is_renamed_into_place_only_when_whole(tmp_path: Path) -> None:
    target = tmp_path / "summary.json"
    target.write_text("old", encoding="utf-8")
    with pytest.raises(RuntimeError, match="interrupted"):
        with atomic_open(target) as handle:
            handle.write("half of the new")
            raise RuntimeError("interrupted")
    assert target.read_text(encoding="utf-8") == "old"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["summary.json"]
    with atomic_open(target) as handle:
        handle.write("new")
    assert target.read_text(encoding="utf-8") == "new"
    with atomic_path(tmp_path / "figure.png") as temporary:
        assert temporary.suffix == ".png" and temporary.name.startswith(".figure.png.")
        temporary.write_bytes(b"png")
    assert (tmp_path / "figure.png").read_bytes() == b"png"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["figure.png", "summary.json"]


def test_a_killed_writers_temporary_is_found(tmp_path: Path) -> None:
    left = tmp_path / ".run.jsonl.abc123.part.jsonl"
    left.write_text("{", encoding="utf-8")
    (tmp_path / "run.jsonl").write_text("{}\n", encoding="utf-8")
    assert stale_temporaries(tmp_path, "run.jsonl") == [left]
    assert stale_temporaries(tmp_path, "tree.svg") == []


def test_a_full_disk_abandons_the_run_log_without_a_half_file(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    path = tmp_path / "run.jsonl"
    log = RunLog(path)
    log.write({"event": "first"})
    real = log._file
    assert real is not None

    def full(text: str) -> int:
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(real, "write", full)
    log.write({"event": "second"})  # no exception: the run goes on without its log
    log.write({"event": "third"})
    log.close()
    assert log.error == f"{path}: No space left on device"
    assert list(tmp_path.iterdir()) == []


def _disk_full(*args: Any, **kwargs: Any) -> None:
    raise OSError(errno.ENOSPC, "No space left on device")


def test_teach_on_a_full_disk_is_exit_2_and_keeps_the_library(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    demo = Path(app.__file__).parent / "skills" / "demos" / "pick_place.csv"
    monkeypatch.setattr(np, "savez", _disk_full)
    code = app.main(
        ["teach", str(demo), "--label", "my_move", "--space", "absolute", "--force",
         "--library", str(tmp_path / "lib")]
    )  # fmt: skip
    assert code == 2
    err = capsys.readouterr().err
    assert f"{tmp_path / 'lib'}: expected to save the library, got No space left on device" in err
    assert list(tmp_path.iterdir()) == []


def test_a_file_written_whole_gets_a_new_files_mode(tmp_path: Path) -> None:
    # Through mkstemp's 0600 temporary, run.jsonl and the figures had been unreadable to the
    # group and others, beside results.jsonl and run.btlog at 0644.
    old = os.umask(0o022)
    try:
        with atomic_open(tmp_path / "a.txt") as fh:
            fh.write("x")
        with atomic_path(tmp_path / "b.png") as temporary:
            temporary.write_bytes(b"png")
        os.umask(0o077)
        with atomic_open(tmp_path / "c.txt") as fh:
            fh.write("x")
    finally:
        os.umask(old)
    assert stat.S_IMODE((tmp_path / "a.txt").stat().st_mode) == 0o644
    assert stat.S_IMODE((tmp_path / "b.png").stat().st_mode) == 0o644
    assert stat.S_IMODE((tmp_path / "c.txt").stat().st_mode) == 0o600
