"""Tick a leaf (or a tree) against a world, advancing the world between ticks."""

from __future__ import annotations

from dataclasses import dataclass

import py_trees
from py_trees.common import Status

from planner.port import WorldPort


@dataclass(frozen=True)
class TickLog:
    """What happened: the status after each tick and the final feedback."""

    statuses: tuple[Status, ...]
    feedback: str
    sim_time: float

    @property
    def final(self) -> Status:
        """The last status."""
        return self.statuses[-1]


def tick_until(
    behaviour: py_trees.behaviour.Behaviour,
    world: WorldPort,
    dt: float = 1.0 / 60.0,
    max_ticks: int = 2000,
) -> TickLog:
    """Tick ``behaviour`` until it stops RUNNING (or ``max_ticks``), advancing ``world`` by ``dt``.

    The behaviour must already be set up (``setup(world=..., library=..., control_dt=dt)``).
    """
    statuses = []
    for _ in range(max_ticks):
        behaviour.tick_once()
        statuses.append(behaviour.status)
        if behaviour.status != Status.RUNNING:
            break
        world.advance(dt)
    return TickLog(tuple(statuses), behaviour.feedback_message, world.time())
