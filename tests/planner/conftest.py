"""Every planner test starts and ends with an empty blackboard (it is global)."""

from __future__ import annotations

from collections.abc import Iterator

import py_trees
import pytest


@pytest.fixture(autouse=True)
def _empty_blackboard() -> Iterator[None]:
    py_trees.blackboard.Blackboard.clear()
    yield
    py_trees.blackboard.Blackboard.clear()
