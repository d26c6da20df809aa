"""Turning a box about the vertical in two palms: which faces to hold, and in how many steps.

A two-palm lateral grasp holds a box on a pair of opposite side faces. The palms turn with the
box, and the arms reach only so far: the *grip yaw*, the turn of the palms from their natural
pose (pressing along the robot's y axis), must stay within ``+-max_turn``. A box presents a
new pair of faces every quarter turn, so a turn the grip cannot make is made in steps: put the
box down, let go, grasp the pair of faces that suits the next step, turn again.

Angles are radians; yaws are rotations about world z. The object frame's quarter turn ``k``
names a face pair: ``k`` even holds the object's +-y faces (``k = 0``: its +y face on the left
palm), ``k`` odd its +-x faces. The grip yaw of face pair ``k`` on an object at yaw ``psi`` is
``wrap(psi + k pi/2 - robot_yaw)``.

Where the steps of a turn stand: the steps before the last stand at one place, the move's
goal (carry there turned part of the way, then turn in place) or any other place on the table
(carry there turned part of the way, turn in place, then carry to the goal with the last
step's turn; at the move's start, the first carry is a turn in place). Every place holds the
object in the same grips: where an obstacle stands beside the goal, a grip turned half way
there can put an arm into it while another place has room. :func:`move_holds` lists, for a
place, each grasp of a move where it is taken and where it lets go.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = [
    "GRIP_TURN_TOLERANCE_DEG",
    "Hold",
    "grip_options",
    "grip_yaw",
    "held_quarter_turns",
    "lateral_quarter_turns",
    "move_holds",
    "turn_steps",
    "wrap_angle",
    "yaw_of",
]

#: Turns below this are no turn, rad (rounding of measured yaws).
_EPS = 1e-6
#: How far beyond the robot's largest grip turn a grip may be and still make a turn, degrees
#: (a box set down a degree past half way between two face pairs).
GRIP_TURN_TOLERANCE_DEG = 5.0


def wrap_angle(angle: float) -> float:
    """``angle`` wrapped to [-pi, pi), rad."""
    return (float(angle) + math.pi) % (2.0 * math.pi) - math.pi


def yaw_of(quaternion: ArrayLike) -> float:
    """Rotation about world z of a frame's x axis, rad, from a quaternion ``(x, y, z, w)``.

    A frame turned on its side about its y axis (a box flipped about the palms' axis) has its
    x axis near vertical, whose heading is undefined: its yaw is then its y axis's heading
    less a quarter turn, which is the same angle for an upright frame.
    """
    x, y, z, w = (float(v) for v in np.asarray(quaternion, dtype=float))
    x_up = 2.0 * (x * z - w * y)  # world z of the frame's x axis
    y_up = 2.0 * (y * z + w * x)  # world z of its y axis
    if abs(x_up) <= abs(y_up) or abs(x_up) < math.sqrt(0.5):
        return math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))
    return math.atan2(-2.0 * (x * y - w * z), 1.0 - 2.0 * (x * x + z * z))


def grip_yaw(object_yaw: float, quarter_turns: int, robot_yaw: float = 0.0) -> float:
    """The palms' turn from their natural pose holding face pair ``quarter_turns``, rad."""
    return wrap_angle(object_yaw + quarter_turns * math.pi / 2.0 - robot_yaw)


def lateral_quarter_turns(object_yaw: float, turn: float = 0.0, robot_yaw: float = 0.0) -> int:
    """The face pair (quarter turns, in 0..3) to grasp for turning the object by ``turn``.

    Of the four ways to hold the box's side faces, the one whose grip yaw stays smallest
    over the whole turn (the larger of its magnitudes at the start and at the end); ties go to
    the smaller grip yaw at the start, then to the lower ``k``. With no turn, this is the pair
    whose normals lie closest to the robot's y axis.
    """

    return min(range(4), key=lambda k: _grip_cost(object_yaw, k, turn, robot_yaw))


def _grip_cost(
    object_yaw: float, k: int, turn: float, robot_yaw: float
) -> tuple[float, float, int]:
    """Face pair ``k``'s rank for a turn: its largest grip yaw over the turn, then its grip yaw
    at the start, then ``k``."""
    start = grip_yaw(object_yaw, k, robot_yaw)
    end = start + turn
    return (round(max(abs(start), abs(end)), 9), round(abs(start), 9), k)


def grip_options(
    object_yaw: float, turn: float, max_turn: float, robot_yaw: float = 0.0
) -> list[int]:
    """The face pairs (quarter turns) that can make a turn of ``turn`` rad, best first:
    :func:`lateral_quarter_turns`'s choice, then each other pair whose grip yaw stays within
    ``+-max_turn`` over the whole turn, in the same order.

    A box turned near half way between two face pairs has two that make a small turn: with one
    of them an arm may reach round into an obstacle where the other stands clear. The first is
    always listed, even when it needs a turn beyond ``max_turn`` (the turn is then made in
    steps, :func:`turn_steps`)."""
    ranked = sorted(range(4), key=lambda k: _grip_cost(object_yaw, k, turn, robot_yaw))
    limit = round(max_turn, 9)
    return ranked[:1] + [
        k for k in ranked[1:] if _grip_cost(object_yaw, k, turn, robot_yaw)[0] <= limit
    ]


def held_quarter_turns(left_palm_in_object: ArrayLike) -> int:
    """The face pair (quarter turns, in 0..3) the left palm holds, from its position in {O}.

    Face pair ``k`` puts the left palm on the object's +y face turned by ``k`` quarter turns
    about its z axis: at ``(0, +w/2)`` for ``k = 0``, ``(-w/2, 0)`` for ``k = 1``, and so on.
    """
    p = np.asarray(left_palm_in_object, dtype=float)
    angle = math.atan2(float(p[1]), float(p[0])) - math.pi / 2.0
    return round(angle / (math.pi / 2.0)) % 4


def turn_steps(
    start_yaw: float, goal_yaw: float, max_turn: float, robot_yaw: float = 0.0
) -> list[float]:
    """The yaws to put the object down at, in order, to turn it from ``start_yaw`` to
    ``goal_yaw`` holding it within ``+-max_turn`` of grip yaw (the last one is the goal's).

    The turn is the real one, ``wrap(goal - start)`` in [-pi, pi) (a box turned half a turn
    is not the same box for a judge of its real orientation), made in steps of at most
    ``max_turn``. Each step either carries on with the grip it has or, when that grip has no
    room left in the turn's direction, starts from a fresh grasp of the faces a quarter turn
    back (as :func:`lateral_quarter_turns` chooses them); a step ends where the grip reaches
    its limit, so each step is the largest the grip allows.

    Parameters
    ----------
    start_yaw, goal_yaw : float
        The object's yaw now and at the goal, rad.
    max_turn : float
        The largest grip yaw the arms can hold, rad, in [pi/4, pi/2): a box's faces come
        every quarter turn, so a grip that cannot turn an eighth of a turn either way cannot
        reach every yaw.
    robot_yaw : float
        The robot's heading, rad.

    Returns
    -------
    list of float
        Yaws (rad, unwrapped from ``start_yaw``), at least one: ``[start + turn]`` when one
        grasp can make the whole turn.

    Raises
    ------
    ValueError
        If ``max_turn`` is outside [pi/4, pi/2) or a yaw is not finite.
    """
    for label, value in (("start_yaw", start_yaw), ("goal_yaw", goal_yaw)):
        if not math.isfinite(value):
            raise ValueError(f"turn_steps: {label}: expected a finite angle in rad, got {value}")
    if not (math.pi / 4.0 - _EPS <= max_turn < math.pi / 2.0):
        raise ValueError(
            "turn_steps: max_turn: expected an angle in [pi/4, pi/2) rad (45 to 90 deg), "
            f"got {max_turn!r}"
        )
    remaining = wrap_angle(goal_yaw - start_yaw)
    yaw = float(start_yaw)
    if abs(remaining) <= _EPS:
        return [yaw + remaining]
    direction = 1.0 if remaining > 0 else -1.0
    # The first grasp holds the faces nearest the robot's y axis (grip yaw within 45 deg).
    grip = grip_yaw(yaw, lateral_quarter_turns(yaw, 0.0, robot_yaw), robot_yaw)
    steps: list[float] = []
    while abs(remaining) > _EPS:
        room = max_turn - direction * grip
        if room <= _EPS:  # this grip is at its limit: grasp the faces a quarter turn back
            grip -= direction * math.pi / 2.0
            room = max_turn - direction * grip
        step = min(abs(remaining), room, max_turn)
        yaw += direction * step
        grip += direction * step
        remaining -= direction * step
        steps.append(yaw)
    steps[-1] = float(start_yaw) + wrap_angle(goal_yaw - start_yaw)
    return steps


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
