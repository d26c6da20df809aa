"""An open fixture on the table, as the core reads it: four walls around a slot.

The fixture's floor is the table top; its walls stand on it around an inside of ``inner``
(x, y) m, ``wall_thickness`` m thick and ``wall_height`` m tall, the whole turned by ``yaw``
about world z. The walls are boxes in the fixture's frame (origin at the inside's centre on
the table top, z up), in the order +x, -x, +y, -y; the x walls span the outer width.

Positions in the world frame, m; quaternions scalar-last.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from skills.types import Array

#: The walls' names, in :meth:`FixtureSpec.walls` order.
WALL_NAMES: tuple[str, str, str, str] = ("+x", "-x", "+y", "-y")


@dataclass(frozen=True)
class FixtureSpec:
    """A static open fixture: four walls on the table around a slot.

    Attributes
    ----------
    name : str
        Unique name (across objects, obstacles and fixtures).
    position : tuple of float
        (3,) centre of the inside at the floor (on the table top), world frame, m.
    yaw : float
        Turn about world z, rad.
    inner : tuple of float
        (2,) inside extents along the fixture's x and y, m.
    wall_thickness : float
        m.
    wall_height : float
        m, above the floor.
    friction : float
        Lateral friction coefficient of the walls.
    for_object : str
        The object it is made for ("" for none in particular).
    """

    name: str
    position: tuple[float, float, float]
    yaw: float
    inner: tuple[float, float]
    wall_thickness: float
    wall_height: float
    friction: float = 0.3
    for_object: str = ""

    def __post_init__(self) -> None:
        sizes = (*self.inner, self.wall_thickness, self.wall_height)
        if not all(math.isfinite(v) and v > 0 for v in sizes):
            raise ValueError(
                f"FixtureSpec {self.name!r}: expected inner, wall_thickness and wall_height "
                f"> 0, got {self.inner}, {self.wall_thickness}, {self.wall_height}"
            )

    @property
    def quaternion(self) -> tuple[float, float, float, float]:
        """Orientation, scalar-last (a turn of ``yaw`` about z)."""
        return (0.0, 0.0, math.sin(self.yaw / 2.0), math.cos(self.yaw / 2.0))

    def walls(self) -> tuple[Array, Array]:
        """The walls' centres (4, 3) and half extents (4, 3), fixture frame, m."""
        ix, iy = self.inner
        t, h = self.wall_thickness, self.wall_height
        cx, cy = ix / 2.0 + t / 2.0, iy / 2.0 + t / 2.0
        centres = np.array(
            [[cx, 0.0, h / 2], [-cx, 0.0, h / 2], [0.0, cy, h / 2], [0.0, -cy, h / 2]]
        )
        long_x = np.array([t / 2.0, iy / 2.0 + t, h / 2.0])
        long_y = np.array([ix / 2.0, t / 2.0, h / 2.0])
        return centres, np.array([long_x, long_x, long_y, long_y])

    def outer(self) -> tuple[float, float]:
        """Outside extents along the fixture's x and y, m."""
        return (self.inner[0] + 2 * self.wall_thickness, self.inner[1] + 2 * self.wall_thickness)

    def to_fixture(self, points: Array) -> Array:
        """World points (..., 3) in the fixture's frame, m."""
        p = np.asarray(points, dtype=float) - np.asarray(self.position)
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        x = c * p[..., 0] + s * p[..., 1]
        y = -s * p[..., 0] + c * p[..., 1]
        return np.stack([x, y, p[..., 2]], axis=-1)

    def wall_of(self, points: Array) -> NDArray[np.intp]:
        """Index (...,) into :data:`WALL_NAMES` of the wall nearest each world point: the one
        whose inner face the point is least inside of (a point on a wall's top counts too)."""
        q = self.to_fixture(points)
        ix, iy = self.inner
        dx = np.abs(q[..., 0]) - ix / 2.0
        dy = np.abs(q[..., 1]) - iy / 2.0
        x_wall = np.where(q[..., 0] >= 0, 0, 1)
        y_wall = np.where(q[..., 1] >= 0, 2, 3)
        return np.asarray(np.where(dx >= dy, x_wall, y_wall), dtype=np.intp)


__all__ = ["WALL_NAMES", "FixtureSpec"]
