"""What a trial draws for a tray carried with balls loose on it (``worlds/tray_carry.yaml``):
the tray's height under the palms' rule, and each ball's start on the floor, radius and mass.

The tray's extents and mass come from ``trials.size_scale`` and ``trials.mass_kg``
(:mod:`experiment.flip_draws`); its height is then kept at least :func:`least_tray_height`,
since the palms squeeze the walls at the tray's centre height and their long side stands
vertical: a lower tray would put them on the table. Its floor and rim keep the file's
thickness. The balls (``trials.riders``, :class:`worlds.trial_schema.RiderTrials`) come from a
generator of their own (``[seed, trial, RIDER_STREAM, redraw]``), so a world without riders or
a size draw draws the same starts, goals and spheres as before they existed, and its balls
keep their place on the tray.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from skills import quaternion as quat
from worlds.spec import ShapeSpec
from worlds.trays import TrayFrame
from worlds.trial_schema import RiderTrials
from worlds.world_file import SphereShape, TrayShape, World

__all__ = [
    "PALM_TABLE_GAP_M",
    "RIDER_STREAM",
    "least_tray_height",
    "place_riders",
    "tray_height",
    "tray_layout_problem",
]

#: The third seed word of the riders' generator (1: turns, 2: redraws, 3: sizes and fixtures).
RIDER_STREAM = 4
#: Least gap between a palm's lower edge and the table when it squeezes a tray's walls, m.
PALM_TABLE_GAP_M = 0.01
#: Times a trial draws the balls' starts again before giving up on keeping them apart.
RIDER_ATTEMPTS = 100


def least_tray_height(palm_length: float) -> float:
    """The lowest tray the palms can squeeze, m: they hold its walls at its centre height with
    their long side (``palm_length`` m, the palm's x extent) vertical, so half the tray's height
    must exceed half that side by :data:`PALM_TABLE_GAP_M`."""
    return palm_length + 2.0 * PALM_TABLE_GAP_M


def tray_height(file_height: float, scaled_height: float, palm_length: float) -> float:
    """A drawn tray's height, m: the scaled one, but never below :func:`least_tray_height` or,
    if the file's tray is lower than that already, below the file's."""
    return max(scaled_height, min(file_height, least_tray_height(palm_length)))


def _tray_shape(tray: TrayShape, size: Sequence[float] | np.ndarray) -> ShapeSpec:
    return ShapeSpec.tray(size, tray.floor, tray.rim)


def _radius(world: World, k: int) -> float:
    """The radius of ``world.objects[k]``, a ball riding on the tray (a sphere), m."""
    shape = world.objects[k].shape
    if not isinstance(shape, SphereShape):
        raise ValueError(f"tray_draws: expected a ball (a sphere) at objects[{k}], got {shape}")
    return float(shape.radius)


def _room(inside: TrayFrame, radius: float, gap: float) -> np.ndarray:
    """How far a ball's centre can go from the tray's centre along x and y, (2,), m."""
    return np.asarray(inside.inner_half, dtype=float) - radius - gap


def tray_layout_problem(base: World, riding: Sequence[int]) -> str | None:
    """Why trials cannot draw ``base``'s tray and balls (``riding``: the balls' indices in
    ``base.objects``), as "field: expected ..., got ..." naming the field; None if they can.

    The smallest tray the trials draw (every factor of ``size_scale`` at its low end) must
    hold the largest ball they draw with ``riders.wall_gap`` left to each wall.
    """
    layout = base.trials
    obj = base.objects[0]
    tray = obj.shape
    if layout.riders is not None and (not isinstance(tray, TrayShape) or not riding):
        return (
            "trials.riders: expected objects[0] to be a tray with a ball loose on it, got "
            f"a {obj.shape.type} ({obj.name!r}) with {len(riding)} ball(s) on it"
        )
    if not isinstance(tray, TrayShape) or not riding:
        return None
    size = np.asarray(tray.size, dtype=float)
    low = 1.0 if layout.size_scale is None else layout.size_scale[0]
    palm = float(base.robot.palm_size[0])
    smallest = np.array([*(size[:2] * low), tray_height(size[2], size[2] * low, palm)])
    riders = layout.riders or RiderTrials()
    gap = riders.wall_gap
    grow = 1.0 if riders.radius_scale is None else riders.radius_scale[1]
    largest = max(_radius(base, k) for k in riding) * grow
    inner = smallest[:2] / 2.0 - tray.rim
    if smallest[2] <= tray.floor or np.any(inner - largest - gap <= 0.0):
        return (
            f"trials.size_scale: expected the smallest tray drawn ({_vec(smallest)} m, "
            f"{tray.rim:g} m walls, {tray.floor:g} m floor) to hold the largest ball "
            f"drawn ({largest:g} m radius, {gap:g} m from each wall), got a low end of {low:g}"
        )
    return None


def _vec(v: np.ndarray) -> str:
    return "[" + ", ".join(f"{x:.3g}" for x in v) + "]"


def place_riders(
    data: dict[str, Any],
    base: World,
    riding: Sequence[int],
    start: np.ndarray,
    size: np.ndarray,
    rng_words: tuple[int, int, int],
) -> None:
    """Put the balls ``riding`` on the tray in a trial's world ``data`` (its JSON form,
    changed in place): on the floor of the tray drawn (extents ``size`` (3,), m, centred on
    ``start`` (3,), world frame, m, turned as in ``base``).

    Without ``trials.riders`` and ``trials.size_scale`` each ball keeps its offset from the
    tray's centre, as trials drew it before either existed. Otherwise each starts at the
    fraction of its room drawn from ``trials.riders`` (or the file's own fraction), radius and
    mass drawn or the file's, lying on the floor. ``rng_words`` is (seed, trial, redraw).

    Raises
    ------
    RuntimeError
        If the balls' drawn starts overlap in every one of :data:`RIDER_ATTEMPTS` draws.
    """
    obj = base.objects[0]
    if not riding or not isinstance(obj.shape, TrayShape):
        return
    if base.trials.riders is None and base.trials.size_scale is None:
        for k in riding:  # the same arithmetic as before: the draws stay bit for bit
            shifted = np.asarray(base.objects[k].pose.position) + start - obj.pose.position
            data["objects"][k]["pose"]["position"] = shifted.tolist()
        return
    seed, trial, redraw = rng_words
    rng = np.random.default_rng([seed, trial, RIDER_STREAM, redraw])
    tray2world = quat.from_rpy(np.radians(obj.pose.rpy_deg))
    file_inside = TrayFrame.of(_tray_shape(obj.shape, obj.shape.size))
    inside = TrayFrame.of(_tray_shape(obj.shape, size))
    riders = base.trials.riders or RiderTrials()
    gap = riders.wall_gap
    radii: list[float] = []
    masses: list[float | None] = []
    fractions: list[np.ndarray] = []
    for k in riding:
        ball = base.objects[k]
        r_file = _radius(base, k)
        scale = riders.radius_scale
        radii.append(r_file if scale is None else r_file * float(rng.uniform(*scale)))
        masses.append(None if riders.mass_kg is None else float(rng.uniform(*riders.mass_kg)))
        # The file's place as a fraction of the file's room, so a scaled tray keeps it inside.
        offset = np.subtract(ball.pose.position, obj.pose.position)
        offset = quat.rotate(quat.conjugate(tray2world), offset)[:2]
        room = _room(file_inside, r_file, gap)
        own = np.where(room > 0.0, offset / np.where(room > 0.0, room, 1.0), np.sign(offset))
        fractions.append(np.clip(own, -1.0, 1.0))
    drawn_axes = [(i, b) for i, b in enumerate((riders.x, riders.y)) if b is not None]
    centres: list[np.ndarray] = []
    for _ in range(RIDER_ATTEMPTS):
        for f in fractions:
            for axis, bounds in drawn_axes:
                f[axis] = rng.uniform(*bounds)
        centres = [
            np.array([*(f * _room(inside, r, gap)), inside.floor_z + r])
            for f, r in zip(fractions, radii, strict=True)
        ]
        if _apart(centres, radii) or not drawn_axes:
            break
    else:
        raise RuntimeError(f"trials.riders: could not draw {len(riding)} balls apart on the tray")
    for k, centre, r, m in zip(riding, centres, radii, masses, strict=True):
        position = np.asarray(start, dtype=float) + quat.rotate(tray2world, centre)
        data["objects"][k]["pose"]["position"] = position.tolist()
        data["objects"][k]["shape"]["radius"] = r
        if m is not None:
            data["objects"][k]["mass"] = m


def _apart(centres: Sequence[np.ndarray], radii: Sequence[float]) -> bool:
    """Whether no two balls overlap."""
    return all(
        np.linalg.norm(centres[i] - centres[j]) >= radii[i] + radii[j]
        for i in range(len(centres))
        for j in range(i)
    )
