"""Where a turn the grip cannot make in one grasp is made: at the move's goal, or elsewhere.

A move that turns the object further than the grip can (:func:`skills.turns.turn_steps`) is
made in steps, putting the object down and grasping another pair of faces between them. The
steps before the last stand at one place: the move's goal (carry there turned part of the
way, then turn in place) or any other place on the table (carry there turned part of the way,
turn in place, then carry to the goal with the last step's turn; at the move's start, the
first carry is a turn in place). Every place holds the object in the same grips: where an
obstacle stands beside the goal, a grip turned half way there can put an arm into it while
another place has room.

:func:`move_holds` lists, for either place, each grasp of the move at its start and its end:
what a world checks to choose the place (``worlds.sim_world.SimWorld.task_moves``) and what a
trial layout keeps obstacles clear of.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from skills.turns import grip_yaw, lateral_quarter_turns, turn_steps

__all__ = ["Hold", "move_holds"]


@dataclass(frozen=True)
class Hold:
    """The object held in a lateral grasp at one place of a move.

    Attributes
    ----------
    position : ndarray, shape (3,)
        The object's centre, world frame, m.
    object_yaw : float
        The object's yaw, rad.
    grip_yaw : float
        The palms' turn from their natural pose (:mod:`skills.turns`), rad.
    quarter_turns : int
        The face pair held (:func:`skills.turns.lateral_quarter_turns`): even, the object's
        +-y faces; odd, its +-x faces.
    """

    position: NDArray[np.float64]
    object_yaw: float
    grip_yaw: float
    quarter_turns: int


def move_holds(
    start: ArrayLike,
    start_yaw: float,
    goal: ArrayLike,
    goal_yaw: float,
    max_turn: float,
    robot_yaw: float = 0.0,
    place: ArrayLike | None = None,
) -> list[Hold]:
    """Each grasp of a move, where it is taken and where it lets go, in order.

    Parameters
    ----------
    start, goal : array_like
        (3,) the object's centre before and after the move, world frame, m.
    start_yaw, goal_yaw : float
        Its yaw before and after, rad.
    max_turn : float
        The robot's largest grip turn, rad (:func:`skills.turns.turn_steps`).
    robot_yaw : float
        The robot's heading, rad.
    place : array_like, optional
        (3,) where the object's centre stands for the steps before the last, m; None: at
        the goal.

    Returns
    -------
    list of Hold
        Two per grasp (taken, let go); two in all for a move one grasp makes.
    """
    start_at = np.asarray(start, dtype=float).reshape(3)
    goal_at = np.asarray(goal, dtype=float).reshape(3)
    turn_at = goal_at if place is None else np.asarray(place, dtype=float).reshape(3)
    steps = turn_steps(start_yaw, goal_yaw, max_turn, robot_yaw)
    holds: list[Hold] = []
    yaw = float(start_yaw)
    for i, step in enumerate(steps):
        last = i == len(steps) - 1
        taken = start_at if i == 0 else turn_at
        left = goal_at if last else turn_at
        k = lateral_quarter_turns(yaw, step - yaw, robot_yaw)
        first = grip_yaw(yaw, k, robot_yaw)
        holds.append(Hold(taken, yaw, first, k))
        holds.append(Hold(left, step, first + (step - yaw), k))
        yaw = step
    return holds
