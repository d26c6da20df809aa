"""The tray carry's criteria (issue 19): the tray kept level, its loose balls kept on it.

Beside the paper's criteria (:mod:`experiment.judge`), a run that carries a rimmed tray with
balls loose on it succeeds only if the tray's tilt (the angle between its z axis and the
world's) never exceeds :data:`MAX_TILT_DEG`, and every ball stays on the tray at every
control step: its centre, in the tray's frame, over the tray's inner footprint and not above
the rim by more than its radius. The record gives the peak tilt and each ball's path relative
to the tray: its largest horizontal excursion from the tray's centre and how many samples it
was off.

The functions here are pure (arrays in, verdict out); :func:`tray_verdicts` reads the samples
the episode's grip recorder took of every object once per control step.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from experiment.grip_recorder import GripRecorder
from skills import quaternion as quat
from skills.level_carry import MAX_TILT_RAD
from worlds.spec import ObjectSpec
from worlds.trays import TrayFrame, riders

#: Largest tilt of the tray allowed at any control step, degrees.
MAX_TILT_DEG = float(np.degrees(MAX_TILT_RAD))


@dataclass(frozen=True)
class TrayVerdict:
    """What one tray and one ball on it did over a run.

    Attributes
    ----------
    tray, ball : str
        The objects' names.
    peak_tilt_deg : float
        Largest angle between the tray's z axis and the world's, degrees.
    max_excursion_m : float
        Largest horizontal distance of the ball's centre from the tray's centre, tray frame, m.
    off_samples : int
        Control steps with the ball off the tray.
    samples : int
        Control steps judged.
    failure : str
        Why the run fails on this tray ("" if it does not).
    """

    tray: str
    ball: str
    peak_tilt_deg: float
    max_excursion_m: float
    off_samples: int
    samples: int
    failure: str = ""

    @property
    def ok(self) -> bool:
        """Whether the tray stayed level and the ball on it."""
        return not self.failure

    def summary(self) -> dict[str, Any]:
        """JSON-ready record."""
        return {
            "tray": self.tray,
            "ball": self.ball,
            "peak_tilt_deg": round(self.peak_tilt_deg, 3),
            "ball_max_excursion_m": round(self.max_excursion_m, 4),
            "ball_off_samples": self.off_samples,
            "samples": self.samples,
        }


def in_tray_frame(
    tray_positions: ArrayLike, tray_quaternions: ArrayLike, points: ArrayLike
) -> np.ndarray:
    """Points (N, 3), world frame, m, in the tray's frame at each sample, (N, 3), m."""
    p = np.asarray(points, dtype=float) - np.asarray(tray_positions, dtype=float)
    return quat.rotate(quat.conjugate(np.asarray(tray_quaternions, dtype=float)), p)


def off_tray(relative: ArrayLike, inside: TrayFrame, radius: float) -> np.ndarray:
    """Per sample (N,), whether a ball of ``radius`` m whose centre is at ``relative`` (N, 3),
    tray frame, m, is off the tray: beyond the inner footprint, or above the rim by more than
    its radius."""
    r = np.asarray(relative, dtype=float).reshape(-1, 3)
    half = np.asarray(inside.inner_half, dtype=float)
    beyond = np.any(np.abs(r[:, :2]) > half, axis=1)
    return np.asarray(beyond | (r[:, 2] > inside.rim_z + radius))


def judge_tray(
    tray: str,
    ball: str,
    inside: TrayFrame,
    radius: float,
    tray_positions: ArrayLike,
    tray_quaternions: ArrayLike,
    ball_positions: ArrayLike,
    max_tilt_deg: float = MAX_TILT_DEG,
) -> TrayVerdict:
    """The verdict on one tray and one ball from their sampled poses, world frame.

    Parameters
    ----------
    tray, ball : str
        Names, for the record.
    inside : TrayFrame
        The tray's inside.
    radius : float
        The ball's radius, m.
    tray_positions, tray_quaternions, ball_positions : array_like
        (N, 3) m, (N, 4) scalar-last and (N, 3) m, one row per control step.
    max_tilt_deg : float
        Largest tilt allowed, degrees.
    """
    q = np.asarray(tray_quaternions, dtype=float).reshape(-1, 4)
    n = q.shape[0]
    if n == 0:
        return TrayVerdict(tray, ball, 0.0, 0.0, 0, 0, f"{tray}: no samples")
    tilt = np.degrees(quat.tilt(q))
    relative = in_tray_frame(tray_positions, q, ball_positions)
    off = off_tray(relative, inside, radius)
    peak = float(np.max(tilt))
    excursion = float(np.max(np.hypot(relative[:, 0], relative[:, 1])))
    failure = ""
    if peak > max_tilt_deg:
        step = int(np.argmax(tilt > max_tilt_deg))
        failure = f"{tray} tilted {peak:.1f} deg > {max_tilt_deg:g} (from sample {step})"
    elif off.any():
        step = int(np.argmax(off))
        failure = f"{ball} left {tray} ({int(off.sum())} samples off, from sample {step})"
    return TrayVerdict(tray, ball, peak, excursion, int(off.sum()), n, failure)


def tray_verdicts(
    objects: Sequence[ObjectSpec], carried: Sequence[str], grip: GripRecorder
) -> list[TrayVerdict]:
    """A verdict per carried tray and ball riding on it at the start, from the samples the
    episode's grip recorder took (every object, every control step)."""
    verdicts = []
    for tray in (o for o in objects if o.name in carried and o.shape.is_tray):
        inside = TrayFrame.of(tray.shape)
        rows = np.asarray(grip.object_rows[tray.name], dtype=float).reshape(-1, 15)
        for ball in riders(objects, tray.name, carried):
            b = np.asarray(grip.object_rows[ball.name], dtype=float).reshape(-1, 15)
            verdicts.append(
                judge_tray(
                    tray.name,
                    ball.name,
                    inside,
                    ball.shape.radius,
                    rows[:, 0:3],
                    rows[:, 3:7],
                    b[:, 0:3],
                )
            )
    return verdicts


__all__ = [
    "MAX_TILT_DEG",
    "TrayVerdict",
    "in_tray_frame",
    "judge_tray",
    "off_tray",
    "tray_verdicts",
]
