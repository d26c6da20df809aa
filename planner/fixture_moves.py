"""Moves into a fixture, as the planner sees them: the grasp height and the hover goal.

A move that seats its object in a fixture (``Move.fixture``) is carried in two parts: the
composition carries the box to a hover goal above its seated pose (clear of the walls), then
the Insert leaf lowers it in. The palms hold the box high enough up its faces to stay above
the walls once it is seated (:func:`skills.insertion.grasp_height`). The formulas are in
:mod:`skills.insertion`; this module reads their inputs from the world port.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from planner.port import FixtureInfo, Move, ObjectSensing, PalmControl, Pose
from skills.insertion import grasp_height, hover_height


def fixture_named(world: ObjectSensing, fixture: str) -> FixtureInfo:
    """The world's fixture called ``fixture``; LookupError naming the ones there are."""
    for f in world.fixtures():
        if f.name == fixture:
            return f
    names = ", ".join(repr(f.name) for f in world.fixtures()) or "none"
    raise LookupError(f"expected a fixture named {fixture!r}; the world has {names}")


def fixture_grasp_height(world: ObjectSensing, palms: PalmControl, name: str) -> float:
    """Height of the palms' centres above object ``name``'s centre, m: high enough to clear
    the walls of every fixture made for it once seated; 0 without one."""
    walls = [f.wall_height for f in world.fixtures() if f.for_object == name]
    if not walls:
        return 0.0
    box_height = float(world.object_extents(name)[2])
    palm_length = float(palms.robot_capabilities().palm_size_m[0])
    return grasp_height(box_height, palm_length, max(walls))


def hover_goal(world: ObjectSensing, move: Move) -> Pose:
    """The goal above a fixture move's seated goal where its descent starts
    (:func:`skills.insertion.hover_height` above it); the goal itself for another move."""
    if move.fixture is None:
        return move.goal
    fixture = fixture_named(world, move.fixture)
    up = np.array([0.0, 0.0, hover_height(fixture.wall_height)])
    return Pose(move.goal.position + up, move.goal.orientation)


def hover_move(world: ObjectSensing, move: Move) -> Move:
    """``move`` with its goal at :func:`hover_goal`."""
    return replace(move, goal=hover_goal(world, move))


__all__ = ["fixture_grasp_height", "fixture_named", "hover_goal", "hover_move"]
