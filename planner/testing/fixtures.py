"""Pytest plugin: fixtures for testing one leaf against the in-memory world, and the ``sim``
marker.

Installed, the package registers it through its ``pytest11`` entry point; otherwise load it
with ``-p planner.testing.fixtures`` or ``pytest_plugins = ["planner.testing.fixtures"]``.
It imports no simulator (:mod:`worlds.testing` is the PyBullet half)::

    def test_my_leaf(fake_world, library, tick_leaf):
        log = tick_leaf(MyLeaf("mine"), fake_world, object="parcel")
        assert log.final == Status.SUCCESS
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from typing import Any

import numpy as np
import py_trees
import pytest

from planner.port import Move, ObstacleInfo, Pose, WorldPort
from planner.testing.fake_world import FakeObject, FakeWorld
from planner.testing.harness import CONTROL_DT, TickLog, set_up, tick_until
from skills import quaternion as quat
from skills.default_library import build_default_library
from skills.library import SkillLibrary

#: The marker of tests that run PyBullet (``-m "not sim"`` skips them).
SIM_MARKER = "sim: runs PyBullet in DIRECT mode (slower)"


def pytest_configure(config: pytest.Config) -> None:
    """Register the ``sim`` marker, unless the suite's ini file declares it already."""
    declared = {str(line).split(":", 1)[0].strip() for line in config.getini("markers")}
    if "sim" not in declared:
        config.addinivalue_line("markers", SIM_MARKER)


def paper_moves() -> dict[str, tuple[Move, ...]]:
    """Centre, right, left: the paper's three consecutive moves, the last two with obstacles."""
    return {
        "parcel": (
            Move(Pose.of([0.65, 0.0, 0.675])),
            Move(Pose.of([0.60, -0.15, 0.675]), ("ball_right",)),
            Move(
                Pose.of([0.60, 0.15, 0.675], quat.from_axis_angle([0, 0, 1], 0.3)),
                ("ball_left",),
            ),
        )
    }


@pytest.fixture
def clean_blackboard() -> Iterator[None]:
    """py_trees' blackboard is global: start and end the test with it empty."""
    py_trees.blackboard.Blackboard.clear()
    yield
    py_trees.blackboard.Blackboard.clear()


@pytest.fixture(scope="session")
def library() -> SkillLibrary:
    """The default library, learnt once per session from the shipped demonstrations."""
    return build_default_library()


@pytest.fixture
def fake_world(clean_blackboard: None) -> FakeWorld:
    """A parcel on the table, two obstacles and the paper's three-move task."""
    return FakeWorld(
        objects=[FakeObject("parcel", np.array([0.20, 0.30, 0.15]))],
        obstacles=[
            ObstacleInfo("ball_right", np.array([0.625, -0.075, 0.81]), 0.04),
            ObstacleInfo("ball_left", np.array([0.74, 0.0, 0.80]), 0.04),
        ],
        moves=paper_moves(),
    )


@pytest.fixture
def tick_leaf(library: SkillLibrary) -> Callable[..., TickLog]:
    """``tick_leaf(leaf, world, max_ticks=2000, **ports)``: wire, set up and tick to the end.

    Port values in braces (``plan="{plan}"``) name blackboard keys; others are constants.
    The world advances one control period between ticks.
    """

    def tick(leaf: Any, world: WorldPort, max_ticks: int = 2000, **ports: Any) -> TickLog:
        return tick_until(set_up(leaf, world, library, **ports), world, CONTROL_DT, max_ticks)

    return tick
