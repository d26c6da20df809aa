"""Rimmed trays and the loose balls that ride on them, from a world's specification.

A ball rides on a tray when it is a sphere that the task does not carry itself and that
starts inside the tray: its centre over the tray's inner footprint, between the floor and the
rim's top. The simulated world tells the planner about it (:meth:`SimWorld.loose_balls`), the
episode's judge watches it (:mod:`experiment.tray`), and trials move it with the tray's start.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from skills import quaternion as quat
from skills.level_carry import LooseBall
from worlds.spec import ObjectSpec, Shape, ShapeSpec


@dataclass(frozen=True)
class TrayFrame:
    """A tray's inside, in its own frame {T} (centre of its outer box, z up), m.

    Attributes
    ----------
    inner_half : tuple of float
        (2,) half extents of the floor between the walls, along x and y of {T}.
    floor_z : float
        Height of the floor's top in {T}.
    rim_z : float
        Height of the walls' top in {T}.
    """

    inner_half: tuple[float, float]
    floor_z: float
    rim_z: float

    @staticmethod
    def of(shape: ShapeSpec) -> TrayFrame:
        """The inside of a tray shape (ValueError if it is not a tray)."""
        if not shape.is_tray:
            raise ValueError(f"TrayFrame: expected a tray shape, got {shape.kind} {shape}")
        x, y, z = shape.size
        return TrayFrame(
            (x / 2.0 - shape.rim, y / 2.0 - shape.rim), -z / 2.0 + shape.floor, z / 2.0
        )

    def loose_ball(self, radius: float) -> LooseBall:
        """The level carry's view of a ball of ``radius`` m in this tray: the rim's height
        above the floor and the longest roll across it (the floor's diagonal less the ball's
        diameter)."""
        diagonal = 2.0 * math.hypot(*self.inner_half)
        return LooseBall(radius, self.rim_z - self.floor_z, max(diagonal - 2.0 * radius, 0.0))


def to_tray_frame(tray: ObjectSpec, point: Sequence[float]) -> np.ndarray:
    """``point`` (3,) world frame, m, in the tray's frame at its initial pose, (3,)."""
    q = np.asarray(tray.quaternion, dtype=float)
    return quat.rotate(quat.conjugate(q), np.asarray(point, float) - np.asarray(tray.position))


def riders(objects: Sequence[ObjectSpec], tray: str, carried: Sequence[str]) -> list[ObjectSpec]:
    """The spheres riding loose on the object ``tray`` at the start, not in ``carried`` (the
    task's objects); empty if ``tray`` is not a tray."""
    own = next(o for o in objects if o.name == tray)
    if not own.shape.is_tray:
        return []
    inside = TrayFrame.of(own.shape)
    out = []
    for obj in objects:
        if obj.name == tray or obj.name in carried or obj.shape.kind != Shape.SPHERE:
            continue
        p = to_tray_frame(own, obj.position)
        over = bool(np.all(np.abs(p[:2]) <= np.asarray(inside.inner_half)))
        if over and inside.floor_z <= p[2] <= inside.rim_z + obj.shape.radius:
            out.append(obj)
    return out


__all__ = ["TrayFrame", "riders", "to_tray_frame"]
