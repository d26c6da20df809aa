"""The generated-URDF cache trusts nothing it did not write."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from worlds.robots.cache import cached_urdf

TEXT = '<robot name="r"><link name="palm"><contact><lateral_friction value="0.8"/></contact>'


def test_a_planted_or_truncated_file_is_written_again(tmp_path: Path) -> None:
    path = cached_urdf(TEXT, "arm", tmp_path)
    assert path.read_text() == TEXT
    path.write_text(TEXT.replace("0.8", "0.0"))  # planted under its name: same length
    assert cached_urdf(TEXT, "arm", tmp_path).read_text() == TEXT
    path.write_text(TEXT[:10])  # a crash mid-write
    assert cached_urdf(TEXT, "arm", tmp_path).read_text() == TEXT
    assert sorted(p.name for p in tmp_path.iterdir()) == [path.name]  # no temporary left


def test_a_linked_file_is_replaced_not_followed(tmp_path: Path) -> None:
    path = cached_urdf(TEXT, "arm", tmp_path / "cache")
    target = tmp_path / "elsewhere.urdf"
    target.write_text(TEXT)
    path.unlink()
    path.symlink_to(target)
    assert cached_urdf(TEXT, "arm", tmp_path / "cache") == path
    assert not path.is_symlink() and path.read_text() == TEXT


def test_a_folder_that_is_a_link_or_another_users_is_refused(tmp_path: Path) -> None:
    real = tmp_path / "real"
    real.mkdir()
    link = tmp_path / "link"
    link.symlink_to(real)
    with pytest.raises(OSError, match="expected a folder for cached robot files"):
        cached_urdf(TEXT, "arm", link)
    if os.getuid() != 0:
        pytest.skip("only root can give a folder to another user")
    other = tmp_path / "other"
    other.mkdir()
    os.chown(other, 4242, -1)
    with pytest.raises(OSError, match="expected a folder of this user's"):
        cached_urdf(TEXT, "arm", other)
