"""The verdict of one run: the paper's criteria, in their order, on what the physics measured.

A run succeeds only if every move of the task is placed within :data:`PLACE_TOLERANCE_M` and
:data:`PLACE_TOLERANCE_DEG` of its goal (the object's measured pose), each object still lies
within the same of where its last move left it when the run ends, each object the task leaves
standing lies within the same of where it stood, nothing touched an obstacle (PyBullet
contacts every physics step, FCL clearance every control step), the arms never touched, and
the tree succeeded. A dropped object fails the run unless the tree picked it up again and
placed it.
"""

from __future__ import annotations

from collections.abc import Sequence

from py_trees.common import Status

from planner.runner import RunResult
from worlds.safety_monitor import SafetyRecord
from worlds.sim_world import SimWorld

PLACE_TOLERANCE_M = 0.02
PLACE_TOLERANCE_DEG = 10.0
#: How a failure names an object the task leaves standing that the run shoved.
STANDING_SUFFIX = "from where it stood (the task does not move it)"
#: Why a closest approach above 0 can stand beside obstacle contacts: two measures, not a
#: clash (a run's and a campaign's summaries say it).
CLOSEST_VS_CONTACTS = (
    "the collision model's distance, every control step; the contacts are PyBullet's, every "
    "physics step, within its contact margin"
)


def move_labels(objects: list[str]) -> list[str]:
    """``"<object> move <n>"`` per move of the task, numbered from 1 within each object."""
    count: dict[str, int] = {}
    labels = []
    for name in objects:
        count[name] = count.get(name, 0) + 1
        labels.append(f"{name} move {count[name]}")
    return labels


def judge(
    result: RunResult,
    sim: SimWorld,
    objects: list[str],
    errors_m: list[float | None],
    errors_deg: list[float | None],
    moved: Sequence[tuple[str, float, float]] = (),
    standing: Sequence[tuple[str, float, float]] = (),
    off_table: Sequence[str] = (),
) -> tuple[bool, str]:
    """Success and the first failure reason, in the order the paper's criteria are listed.

    ``objects``, ``errors_m`` and ``errors_deg`` hold one entry per move of the task, in task
    order: a move without a placement is a failure naming its object and move, whatever the
    tree said. A drop fails the run only if the task then went wrong in any way (it is the
    reason given, being the cause); a dropped object that the tree picked up again and placed,
    with nothing touched, is a recovery: the run succeeds and its record says ``dropped``.
    ``moved`` holds, per object, how far (m) and how much (deg) it lies at the end from where
    its last move placed it: a placed object knocked away afterwards fails the run.
    ``standing`` holds the same for each object the task does not move (nor carries on
    another), from where it stood at the start: a bystander shoved by an arm or by the carried
    object fails the run too. ``off_table`` says, per object, that it ends off the table (a
    fall no palm caused by letting go: knocked off): a failed run gives it as its reason
    after a drop, as what the rest follows from.
    """
    s = sim.safety
    if s.spawned_inside:
        # First: what it causes (a drop, a contact) is not the reason.
        where = "; ".join(f"{o} inside {', '.join(b)}" for o, b in sorted(s.spawned_inside.items()))
        return False, f"obstacle spawned inside a body: {where}"
    ok, failure = _task_outcome(result, s, objects, errors_m, errors_deg)
    knocked = knocked_away(moved, standing)
    if ok and knocked:
        ok, failure = False, knocked[-1]
    if not ok and s.dropped:
        return False, f"dropped {s.dropped_object}" if s.dropped_object else "dropped"
    if not ok and off_table:
        return False, off_table[0]
    return ok, failure


def knocked_away(
    moved: Sequence[tuple[str, float, float]], standing: Sequence[tuple[str, float, float]]
) -> list[str]:
    """The judge's words for each object ``moved`` (m, deg) beyond the placement tolerance
    from where it was placed, or ``standing`` from where it stood: ``parcel moved 35.0 cm,
    68.7 deg after it was placed``: a success's failure (the last of them), and said under
    a failure whose reason is another (a run that failed so had not said that an approach
    swept its placed parcel 35 cm across the table)."""
    return [
        f"{name} moved {metres * 100:.1f} cm, {degrees:.1f} deg {said}"
        for rows, said in ((moved, "after it was placed"), (standing, STANDING_SUFFIX))
        for name, metres, degrees in rows
        if metres > PLACE_TOLERANCE_M or degrees > PLACE_TOLERANCE_DEG
    ]


def _task_outcome(
    result: RunResult,
    s: SafetyRecord,
    objects: list[str],
    errors_m: list[float | None],
    errors_deg: list[float | None],
) -> tuple[bool, str]:
    """:func:`judge` without the spawn and drop criteria."""
    if s.obstacle_contacts:
        return False, "obstacle contact: " + ", ".join(sorted(s.obstacle_contacts))
    if s.min_obstacle_distance_m < 0.0:
        # PyBullet makes no contact between a fixed base and a static body; FCL still sees
        # them overlap (a negative clearance, measured every control step).
        depth = -s.min_obstacle_distance_m * 1000.0
        return False, f"obstacle penetration: {s.closest} overlap by {depth:.1f} mm (FCL)"
    if s.arm_contacts:
        return False, "arms touched"
    if result.status is Status.INVALID:  # halted by the run's time or wall-clock limit
        return False, f"stopped: {result.reason}"
    if not result.success:
        return False, f"tree {result.status.value.lower()}: {result.reason}"
    labels = move_labels(objects)
    undone = [
        label
        for label, e, d in zip(labels, errors_m, errors_deg, strict=True)
        if e is None or d is None
    ]
    if undone:
        return False, "not placed: " + ", ".join(undone)
    for label, e, d in zip(labels, errors_m, errors_deg, strict=True):
        assert e is not None and d is not None
        if e > PLACE_TOLERANCE_M or d > PLACE_TOLERANCE_DEG:
            return False, f"{label} placed {e * 100:.1f} cm, {d:.1f} deg from its goal"
    return True, ""


__all__ = [
    "PLACE_TOLERANCE_DEG",
    "PLACE_TOLERANCE_M",
    "STANDING_SUFFIX",
    "judge",
    "knocked_away",
    "move_labels",
]
