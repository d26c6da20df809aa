"""Shared fixtures of the worlds tests: the default world file's data, and writing a variant."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest
import yaml

from worlds.testing import DEFAULT_WORLD


@pytest.fixture
def default_data() -> dict[str, Any]:
    """The default world file, parsed: a fresh copy to edit."""
    data = yaml.safe_load(DEFAULT_WORLD.read_text(encoding="utf-8"))
    assert isinstance(data, dict)
    return data


@pytest.fixture
def write_world(tmp_path: Path) -> Callable[[dict[str, Any], str], Path]:
    """Write world data as YAML into ``tmp_path`` under a file name; returns its path."""

    def write(data: dict[str, Any], name: str) -> Path:
        path = tmp_path / name
        path.write_text(yaml.safe_dump(data), encoding="utf-8")
        return path

    return write
