"""Pytest fixture for testing a leaf against a real PyBullet world (DIRECT mode).

``pytest_plugins = ["planner.testing.fixtures", "worlds.testing"]``, then::

    @pytest.mark.sim
    def test_grasp_in_physics(sim_world, tick_leaf):
        log = tick_leaf(Grasp("grasp"), sim_world, object="parcel", state="{state}")
"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest

from worlds.sim_world import SimWorld
from worlds.world_file import load_world

SMALL_WORLD = Path(__file__).resolve().parent / "parcel_pick_place.yaml"


@pytest.fixture
def sim_world(clean_blackboard: None) -> Iterator[SimWorld]:
    """The default world (parcel, table, two arms) in PyBullet DIRECT mode."""
    with SimWorld(load_world(SMALL_WORLD)) as world:
        yield world
