"""What a Transport leaf publishes about its move: plain data on the blackboard.

A Transport leaf that starts carrying an object writes a :class:`MoveResult` (status RUNNING),
and writes it again when it ends: SUCCESS with the placement error, FAILURE, or INVALID when a
parent halts it mid-move. :data:`MOVE_RESULTS_KEY` holds a mapping ``(object, move) ->`` the
latest result of that move, so a move that ends and the next that starts in the same tick are
both seen. :data:`MOVE_PLACEMENTS_KEY` holds each move's latest SUCCESS: a correction that
starts in the tick its move's carry succeeded, then fails, leaves the placement (its error, and
the surface or fixture it found) readable. Readers (the experiment's recorder, after every
tick) read these keys instead of walking the tree for Transport leaves and reading their
ports; the run log shows the writes like any other blackboard write.
"""

from __future__ import annotations

from dataclasses import dataclass

import py_trees
from py_trees.common import Access, Status

__all__ = [
    "MOVE_PLACEMENTS_KEY",
    "MOVE_RESULTS_KEY",
    "MoveResult",
    "move_placements",
    "move_results",
    "publish_move_result",
]

#: Absolute blackboard key of ``dict[(object, move), MoveResult]``, the latest of each move.
MOVE_RESULTS_KEY = "/move_results"
#: Absolute blackboard key of ``dict[(object, move), MoveResult]``, the latest SUCCESS of each.
MOVE_PLACEMENTS_KEY = "/move_placements"


@dataclass(frozen=True)
class MoveResult:
    """One move's composition and outcome, as the Transport leaf that carried it saw it.

    Attributes
    ----------
    object : str
        The carried object.
    move : int
        Index of the task's move, from 0.
    transport_weight : float
        The composition's weight on the pick-and-place skill.
    avoid_gain : float
        The composition's gain on the avoidance skills.
    status : Status
        RUNNING while carrying; SUCCESS, FAILURE, or INVALID (halted) once it ended.
    placement_error_m : float or None
        Object position's distance from the goal at SUCCESS, m; None otherwise.
    placement_error_rad : float or None
        Object orientation's angle from the goal at SUCCESS, rad; None otherwise.
    skill : str or None
        Name of the learnt transport skill the composition ran (its demonstration is the one
        the move generalised), None if it composed none.
    rested_z : float or None
        At SUCCESS after a set-down (the surface was felt above or below where the goal puts
        it), the height of the object's centre resting on it, m; the goal holds it as its
        height from then on. None otherwise.
    found_xy : tuple of float or None
        At SUCCESS of an insertion whose fixture stood off the goal's place (found by touch,
        :class:`planner.leaves.Insert`), where the object's centre was seated, (x, y) m, world
        frame; the goal holds it as its place from then on. None otherwise.
    """

    object: str
    move: int
    transport_weight: float
    avoid_gain: float
    status: Status
    placement_error_m: float | None = None
    placement_error_rad: float | None = None
    skill: str | None = None
    rested_z: float | None = None
    found_xy: tuple[float, float] | None = None


def publish_move_result(result: MoveResult, writer: str) -> None:
    """Make ``result`` its move's latest under :data:`MOVE_RESULTS_KEY` (and, a SUCCESS, under
    :data:`MOVE_PLACEMENTS_KEY`), as client ``writer``."""
    key = (result.object, result.move)
    _write(MOVE_RESULTS_KEY, {**move_results(), key: result}, writer)
    if result.status == Status.SUCCESS:
        _write(MOVE_PLACEMENTS_KEY, {**move_placements(), key: result}, writer)


def _write(key: str, mapping: dict[tuple[str, int], MoveResult], writer: str) -> None:
    client = py_trees.blackboard.Client(name=writer)
    client.register_key(key=key, access=Access.WRITE)
    client.set(key, mapping)  # a new mapping: readers' copies never change
    client.unregister(clear=False)  # the value stays; no client is left behind per write


def _read(key: str) -> dict[tuple[str, int], MoveResult]:
    try:
        value = py_trees.blackboard.Blackboard.get(key)
    except KeyError:
        return {}
    return dict(value) if isinstance(value, dict) else {}


def move_results() -> dict[tuple[str, int], MoveResult]:
    """The latest published :class:`MoveResult` of each ``(object, move)``; empty before any."""
    return _read(MOVE_RESULTS_KEY)


def move_placements() -> dict[tuple[str, int], MoveResult]:
    """The latest SUCCESS of each ``(object, move)`` that has had one; empty before any."""
    return _read(MOVE_PLACEMENTS_KEY)
