"""What a trial draws for a box turned about its grasp axis (``worlds/box_flip.yaml``): each
goal's pitch, and the box's size and mass, from the world's ``trials`` section.

Every draw here comes from a generator of its own (``[seed, trial, 3, redraw]``), so a layout
without pitches, size or mass ranges draws the same starts, goals and spheres as before they
existed.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import replace
from typing import Any

import numpy as np

from skills import quaternion as quat
from skills.flip import vertical_half_extent
from worlds.world_file import GoalRegion, TrialSettings

__all__ = ["ObjectDraw", "draw_object", "goal_half_height", "pitched_goal_postures"]


class ObjectDraw:
    """The object's size (m, (3,)), mass (kg) and each goal's pitch (degrees) for one trial.

    Attributes
    ----------
    size : ndarray, shape (3,)
        The box's extents, m (the file's, scaled when ``size_scale`` is given).
    mass : float or None
        kg, None: the file's.
    pitches : list of float
        One per move, degrees (0 for a region without ``pitch_deg``).
    """

    def __init__(self, size: np.ndarray, mass: float | None, pitches: list[float]) -> None:
        self.size = size
        self.mass = mass
        self.pitches = pitches


def draw_object(
    layout: TrialSettings,
    regions: Sequence[GoalRegion],
    size: Sequence[float],
    seed: int,
    trial: int,
    redraw: int,
) -> ObjectDraw:
    """Draw the box's size and mass and each goal's pitch for trial ``trial``."""
    rng = np.random.default_rng([seed, trial, 3, redraw])
    extents = np.asarray(size, dtype=float)
    if layout.size_scale is not None:
        extents = extents * rng.uniform(*layout.size_scale, size=3)
    mass = None if layout.mass_kg is None else float(rng.uniform(*layout.mass_kg))
    pitches = [
        float(region.pitch_deg[int(rng.integers(len(region.pitch_deg)))])
        if region.pitch_deg
        else 0.0
        for region in regions
    ]
    return ObjectDraw(extents, mass, pitches)


def goal_half_height(size: np.ndarray, pitch_deg: float, yaw_deg: float = 0.0) -> float:
    """Half the box's vertical extent at a goal pitched by ``pitch_deg``: its centre's height
    above the table top when it rests there, m."""
    q = quat.from_rpy(np.radians([0.0, pitch_deg, yaw_deg]))
    return float(vertical_half_extent(size, q))


def pitched_goal_postures(
    postures: list[Any], goal: np.ndarray, half: np.ndarray, pitch_deg: float
) -> list[Any]:
    """``postures`` (:class:`experiment.layout.Posture`, below which this module sits) with
    those at ``goal`` holding the box as turned there: a quarter turn
    about its y axis swaps its x and z extents (about the grasp, the palms' span is the same)."""
    if pitch_deg == 0.0:
        return postures
    c, s = abs(math.cos(math.radians(pitch_deg))), abs(math.sin(math.radians(pitch_deg)))
    turned = np.array([c * half[0] + s * half[2], half[1], s * half[0] + c * half[2]], dtype=float)
    return [
        replace(p, half_extents=turned) if np.allclose(p.position, goal) else p for p in postures
    ]
