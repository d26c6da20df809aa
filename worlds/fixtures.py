"""Fixtures in PyBullet: one static body of four wall boxes, and what its contacts measure.

A fixture (:class:`worlds.fixture_spec.FixtureSpec`) is always present (unlike obstacles),
and the object it is made for may touch it: insertion is contact. The robot may not. What a
run is judged on is read here, every physics step: each wall's normal force on the objects
(:func:`wall_forces`) and whether a robot body touches the fixture.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np
import pybullet as pb
from numpy.typing import ArrayLike

from skills.types import Array
from worlds.fixture_spec import FixtureSpec

#: Colour of a fixture's walls (RGBA).
FIXTURE_RGBA = (0.35, 0.45, 0.6, 1.0)


def create_fixture(client: int, fixture: FixtureSpec) -> int:
    """The fixture's static body (mass 0, one compound collision shape); its body id."""
    centres, halves = fixture.walls()
    n = len(centres)
    col = pb.createCollisionShapeArray(
        shapeTypes=[pb.GEOM_BOX] * n,
        halfExtents=halves.tolist(),
        collisionFramePositions=centres.tolist(),
        physicsClientId=client,
    )
    vis = pb.createVisualShapeArray(
        shapeTypes=[pb.GEOM_BOX] * n,
        halfExtents=halves.tolist(),
        visualFramePositions=centres.tolist(),
        rgbaColors=[list(FIXTURE_RGBA)] * n,
        physicsClientId=client,
    )
    body = pb.createMultiBody(
        0.0,
        col,
        vis,
        basePosition=list(fixture.position),
        baseOrientation=list(fixture.quaternion),
        physicsClientId=client,
    )
    pb.changeDynamics(body, -1, lateralFriction=fixture.friction, physicsClientId=client)
    return int(body)


def _points(client: int, fixture_id: int, body: int) -> tuple[Any, ...]:
    """Contact points with the fixture as body A and ``body`` as B."""
    return tuple(pb.getContactPoints(bodyA=fixture_id, bodyB=body, physicsClientId=client))


def _contact_forces(points: Sequence[Sequence[Any]]) -> Array:
    """Each contact's force (k, 3) N, world frame, that body A exerts on body B: normal and
    friction (the normal points from B to A; A pushes B the other way)."""
    p = np.array([[*c[7], *c[11], *c[13]] for c in points], dtype=float).reshape(-1, 3, 3)
    f = np.array([[c[9], c[10], c[12]] for c in points], dtype=float)
    return -np.einsum("ki,kij->kj", f, p)


def force_on_body(points: Sequence[Sequence[Any]]) -> Array:
    """Total force (3,) N, world frame, that body A of PyBullet contact points exerts on body
    B: normal and friction."""
    if not points:
        return np.zeros(3)
    return np.asarray(_contact_forces(points).sum(axis=0))


def torque_on_body(points: Sequence[Sequence[Any]], centre: ArrayLike) -> Array:
    """Total torque (3,) N m, world frame, about ``centre`` (3,) m, that body A of PyBullet
    contact points exerts on body B, each force acting at its point on B."""
    if not points:
        return np.zeros(3)
    r = np.array([c[6] for c in points], dtype=float) - np.asarray(centre, dtype=float)
    return np.asarray(np.cross(r, _contact_forces(points)).sum(axis=0))


def fixture_force(client: int, fixture_id: int, body: int) -> Array:
    """Force (3,) N, world frame, that the fixture exerts on ``body`` now."""
    return force_on_body(_points(client, fixture_id, body))


def fixture_torque(client: int, fixture_id: int, body: int, centre: ArrayLike) -> Array:
    """Torque (3,) N m, world frame, about ``centre`` that the fixture exerts on ``body`` now."""
    return torque_on_body(_points(client, fixture_id, body), centre)


def wall_forces(client: int, fixture_id: int, fixture: FixtureSpec, body: int) -> Array:
    """Normal force (4,) N of each wall (:data:`worlds.fixture_spec.WALL_NAMES` order) on
    ``body`` now, the walls told apart by where each contact lies on the fixture."""
    points = _points(client, fixture_id, body)
    out = np.zeros(4)
    if not points:
        return out
    where = fixture.wall_of(np.array([c[5] for c in points], dtype=float))
    np.add.at(out, where, np.array([c[9] for c in points], dtype=float))
    return out


__all__ = [
    "FIXTURE_RGBA",
    "create_fixture",
    "fixture_force",
    "fixture_torque",
    "force_on_body",
    "torque_on_body",
    "wall_forces",
]


class FixtureLog:
    """What the monitor measured of the fixtures over a run, every physics step.

    Attributes
    ----------
    dt : float
        Physics period, s: one row per step.
    wall_forces : dict of str to list of ndarray
        Per fixture, each step's normal force (4,) N of each wall on the objects.
    robot_contacts : dict of str to int
        ``"<arm> ~ <fixture>"`` -> physics steps in contact (the robot may not touch one).
    min_robot_distance_m : float
        Smallest FCL distance from an arm link or palm to a fixture's wall, m (every control
        step).
    robot_closest : str
        Which link came closest to which wall.
    """

    def __init__(self, dt: float) -> None:
        self.dt = float(dt)
        self.wall_forces: dict[str, list[Array]] = {}
        self.robot_contacts: dict[str, int] = {}
        self.min_robot_distance_m = math.inf
        self.robot_closest = ""

    def forces(self, fixture: str) -> Array:
        """The walls' forces of ``fixture`` over the run, (steps, 4) N."""
        rows = self.wall_forces.get(fixture, [])
        return np.array(rows) if rows else np.zeros((0, 4))


__all__ += ["FixtureLog"]
