"""The insertion's criteria: the box seated in its fixture, and no wall pressed too long.

A run of a world with a fixture (``fixtures:``) succeeds only if, beyond the paper's criteria
(:mod:`experiment.judge`), at the end of the run each object a task move seats in a fixture

* is seated: its bottom on the fixture's floor (the table top) within
  :data:`SEATED_TOLERANCE_M`, and its pose within :data:`SEATED_TOLERANCE_DEG` of the goal;

and over the whole run

* no wall of a fixture pressed the objects with more than :data:`WALL_FORCE_LIMIT_N` for more
  than :data:`WALL_FORCE_LIMIT_S` at a stretch (each wall on its own, every physics step);
* the robot never touched a fixture.

The record reports each seating error, the peak wall force and the longest stretch above
the limit. The functions here take plain arrays, so the criteria are tested on known cases.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from skills import quaternion as quat

SEATED_TOLERANCE_M = 0.003
SEATED_TOLERANCE_DEG = 3.0
WALL_FORCE_LIMIT_N = 20.0
WALL_FORCE_LIMIT_S = 0.5


def longest_above(forces: ArrayLike, dt: float, limit: float = WALL_FORCE_LIMIT_N) -> float:
    """Longest unbroken stretch any one wall's force is above ``limit``, s.

    Parameters
    ----------
    forces : array_like, shape (steps,) or (steps, walls)
        Each step's force of each wall, N.
    dt : float
        Step period, s.
    """
    f = np.asarray(forces, dtype=float)
    f = f.reshape(f.shape[0], -1) if f.size else np.zeros((0, 1))
    above = np.vstack([np.zeros((1, f.shape[1]), bool), f > limit, np.zeros((1, f.shape[1]), bool)])
    longest = 0
    for column in above.T:  # per wall: a few walls, not a loop over samples
        edges = np.flatnonzero(np.diff(column.astype(np.int8)))
        if edges.size:
            longest = max(longest, int(np.max(edges[1::2] - edges[0::2])))
    return longest * float(dt)


def seating_error(
    position: ArrayLike,
    orientation: ArrayLike,
    goal_position: ArrayLike,
    goal_orientation: ArrayLike,
    half_height: float,
    floor_z: float,
) -> tuple[float, float, float]:
    """How far an object is from seated: its bottom's height above the floor (m, signed), its
    centre's distance from the goal (m) and its angle from the goal's orientation (degrees).
    Half a turn about z counts as seated too (a box fits its slot both ways)."""
    p = np.asarray(position, dtype=float)
    bottom = float(p[2] - half_height - floor_z)
    offset = float(np.linalg.norm(p - np.asarray(goal_position, dtype=float)))
    goal_q = np.asarray(goal_orientation, dtype=float)
    half_turn = quat.multiply(quat.from_axis_angle(np.array([0.0, 0.0, 1.0]), math.pi), goal_q)
    q = np.asarray(orientation, dtype=float)
    angle = min(quat.angle_between(q, goal_q), quat.angle_between(q, half_turn))
    return bottom, offset, math.degrees(float(angle))


@dataclass(frozen=True)
class InsertionVerdict:
    """The insertion's criteria on one run.

    Attributes
    ----------
    ok : bool
    reason : str
        The first criterion failed, in the order of the module's list ("" when ok).
    figures : dict
        JSON-ready: per fixture, ``seat_bottom_m``, ``seat_offset_m``, ``seat_angle_deg``,
        ``peak_wall_force_n``, ``longest_above_limit_s``; and ``robot_contacts``.
    """

    ok: bool
    reason: str
    figures: dict[str, Any]


def judge_insertion(
    seats: dict[str, tuple[float, float, float]],
    wall_forces: dict[str, np.ndarray],
    dt: float,
    robot_contacts: dict[str, int],
) -> InsertionVerdict:
    """The verdict from what a run measured.

    Parameters
    ----------
    seats : dict
        Per fixture, :func:`seating_error` of the object seated in it at the end of the run.
    wall_forces : dict
        Per fixture, each physics step's force of each wall, (steps, 4) N.
    dt : float
        Physics period, s.
    robot_contacts : dict
        ``"<arm> ~ <fixture>"`` -> physics steps in contact.
    """
    figures: dict[str, Any] = {"robot_contacts": dict(robot_contacts)}
    reasons: list[str] = []
    for name, (bottom, offset, angle) in seats.items():
        forces = np.asarray(wall_forces.get(name, np.zeros((0, 4))), dtype=float)
        peak = float(forces.max()) if forces.size else 0.0
        longest = longest_above(forces, dt)
        figures[name] = {
            "seat_bottom_m": round(bottom, 5),
            "seat_offset_m": round(offset, 5),
            "seat_angle_deg": round(angle, 3),
            "peak_wall_force_n": round(peak, 2),
            "longest_above_limit_s": round(longest, 4),
        }
        if abs(bottom) > SEATED_TOLERANCE_M or angle > SEATED_TOLERANCE_DEG:
            reasons.append(
                f"not seated in {name}: bottom {bottom * 1000:.1f} mm above its floor, "
                f"{angle:.1f} deg from the goal (tolerance {SEATED_TOLERANCE_M * 1000:g} mm, "
                f"{SEATED_TOLERANCE_DEG:g} deg)"
            )
        if longest > WALL_FORCE_LIMIT_S:
            reasons.append(
                f"{name}'s wall pressed above {WALL_FORCE_LIMIT_N:g} N for {longest:.2f} s "
                f"(limit {WALL_FORCE_LIMIT_S:g} s; peak {peak:.1f} N)"
            )
    if robot_contacts:
        reasons.append("robot touched a fixture: " + ", ".join(sorted(robot_contacts)))
    return InsertionVerdict(not reasons, reasons[0] if reasons else "", figures)


def insertion_verdict(sim: Any) -> InsertionVerdict | None:
    """:func:`judge_insertion` on a finished :class:`worlds.sim_world.SimWorld`; None for a
    world without fixtures. The objects are measured as they are now (the run's end), against
    the fixtures where the physics put them (:attr:`worlds.scene.Scene.physical`: a Hard
    trial's fixture may stand off its file place, its floor with the true table)."""
    spec = sim.spec
    told = {f.name: f for f in spec.scene.fixtures}
    fixtures = {f.name: f for f in sim.scene.physical.fixtures}
    if not fixtures:
        return None
    seats: dict[str, tuple[float, float, float]] = {}
    for step in spec.task:
        obj = spec.scene.object_named(step.object)
        for move in step.moves:
            if move.fixture is None:
                continue
            position, orientation = sim.scene.object_pose(step.object)
            # The seated goal moves with its fixture.
            shift = np.subtract(fixtures[move.fixture].position, told[move.fixture].position)
            seats[move.fixture] = seating_error(
                position,
                orientation,
                np.asarray(move.goal_position, dtype=float) + shift,
                move.goal_quaternion,
                float(obj.shape.extents()[2]) / 2.0,
                float(fixtures[move.fixture].position[2]),
            )
    log = sim.fixture_log
    forces = {name: log.forces(name) for name in fixtures}
    return judge_insertion(seats, forces, log.dt, dict(log.robot_contacts))


__all__ = [
    "SEATED_TOLERANCE_DEG",
    "SEATED_TOLERANCE_M",
    "WALL_FORCE_LIMIT_N",
    "WALL_FORCE_LIMIT_S",
    "InsertionVerdict",
    "insertion_verdict",
    "judge_insertion",
    "longest_above",
    "seating_error",
]
