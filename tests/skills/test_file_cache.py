"""Cache entries: read back only whole and unaltered, named by everything they derive from."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from skills import file_cache


def test_an_entry_reads_back_its_payload(tmp_path: Path) -> None:
    path = tmp_path / "entry.bin"
    file_cache.write_entry(path, b"\x00payload\xff")
    assert file_cache.read_entry(path) == b"\x00payload\xff"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["entry.bin"]  # no temporary left


def test_a_truncated_altered_or_foreign_entry_reads_as_none(tmp_path: Path) -> None:
    path = tmp_path / "entry.bin"
    file_cache.write_entry(path, b"0123456789")
    whole = path.read_bytes()
    path.write_bytes(whole[:-1])  # a crash mid-write (were it not renamed into place)
    assert file_cache.read_entry(path) is None
    path.write_bytes(whole[:-1] + b"8")  # one byte changed, same length
    assert file_cache.read_entry(path) is None
    path.write_bytes(b"0123456789")  # planted without the header
    assert file_cache.read_entry(path) is None
    assert file_cache.read_entry(tmp_path / "missing.bin") is None
    assert file_cache.read_entry(tmp_path) is None  # a folder


def test_a_link_is_never_read(tmp_path: Path) -> None:
    target = tmp_path / "real.bin"
    file_cache.write_entry(target, b"data")
    link = tmp_path / "link.bin"
    link.symlink_to(target)
    assert file_cache.read_entry(target) == b"data"
    assert file_cache.read_entry(link) is None


def test_a_key_changes_with_any_byte_and_with_where_parts_split() -> None:
    key = file_cache.content_key(["ab", b"c"])
    assert len(key) == 32
    assert key == file_cache.content_key([b"ab", "c"])
    assert key != file_cache.content_key(["a", "bc"])
    assert key != file_cache.content_key(["ab", "d"])


def test_versions_name_installed_and_absent_distributions() -> None:
    numpy_version, absent = file_cache.versions("numpy", "no-such-distribution-duet")
    assert numpy_version.startswith("numpy==") and numpy_version != "numpy==absent"
    assert absent == "no-such-distribution-duet==absent"


def test_source_files_hold_every_module_and_its_bytes(tmp_path: Path) -> None:
    (tmp_path / "sub").mkdir()
    (tmp_path / "a.py").write_text("x = 1\n")
    (tmp_path / "sub" / "b.py").write_text("y = 2\n")
    (tmp_path / "notes.txt").write_text("not source")
    assert file_cache.source_files(tmp_path) == ["a.py", b"x = 1\n", "sub/b.py", b"y = 2\n"]


def test_a_folder_that_is_a_link_is_refused(tmp_path: Path) -> None:
    real = tmp_path / "real"
    real.mkdir()
    link = tmp_path / "link"
    link.symlink_to(real)
    with pytest.raises(OSError, match=r"link: expected a folder for cached hulls, got a link"):
        file_cache.cache_folder("hulls", "cached hulls", link)
    made = file_cache.cache_folder("hulls", "cached hulls", tmp_path / "new")
    assert made.is_dir() and (os.stat(made).st_mode & 0o777) == 0o700
