"""What a Transport leaf publishes about its move: plain data on the blackboard.

A Transport leaf that starts carrying an object writes a :class:`MoveResult` (status RUNNING),
and writes it again when it ends: SUCCESS with the placement error, FAILURE, or INVALID when a
parent halts it mid-move. :data:`MOVE_RESULTS_KEY` holds a mapping ``(object, move) ->`` the
latest result of that move, so a move that ends and the next that starts in the same tick are
both seen. Readers (the experiment's recorder, after every tick) read this key instead of
walking the tree for Transport leaves and reading their ports; the run log shows the writes
like any other blackboard write.
"""

from __future__ import annotations

from dataclasses import dataclass

import py_trees
from py_trees.common import Access, Status

__all__ = ["MOVE_RESULTS_KEY", "MoveResult", "move_results", "publish_move_result"]

#: Absolute blackboard key of ``dict[(object, move), MoveResult]``, the latest of each move.
MOVE_RESULTS_KEY = "/move_results"


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
    """Make ``result`` its move's latest under :data:`MOVE_RESULTS_KEY`, as client ``writer``."""
    results = {**move_results(), (result.object, result.move): result}
    client = py_trees.blackboard.Client(name=writer)
    client.register_key(key=MOVE_RESULTS_KEY, access=Access.WRITE)
    client.set(MOVE_RESULTS_KEY, results)  # a new mapping: readers' copies never change
    client.unregister(clear=False)  # the value stays; no client is left behind per write


def move_results() -> dict[tuple[str, int], MoveResult]:
    """The latest published :class:`MoveResult` of each ``(object, move)``; empty before any."""
    try:
        value = py_trees.blackboard.Blackboard.get(MOVE_RESULTS_KEY)
    except KeyError:
        return {}
    return dict(value) if isinstance(value, dict) else {}
