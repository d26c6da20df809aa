"""Recorded demonstrations made fit to learn from, and a learnt skill checked against its own.

A DMP learns its forcing from the demonstration's accelerations, two finite differences of the
recorded positions. Sensor noise of ``e`` metres at a sampling step ``h`` becomes accelerations
of about ``4 e / h^2``: 0.2 mm at 100 Hz is 8 m/s^2, tens of times a carry's own. The ridge fit
follows that noise with large alternating weights, and where the phase runs past the last
basis centre (after the demonstration's duration) only the last of them is left: a carry
taught from a demonstration with 0.5 mm of noise plunged a metre below its goal there (raw
weights up to 3.4e4; 441 for the same carry without noise).

:func:`low_pass` smooths the samples before anything is differentiated: each becomes the
Gaussian-weighted mean of those near it in time (uneven sampling is fine), the end samples
held beyond the ends, where a demonstration is at rest. :func:`reproduction` rolls a learnt
skill out from its demonstration's own start to its own goal and measures how far it strays,
during and after the demonstration's duration: the check ``app.py teach`` makes before it
saves anything.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from skills import quaternion as quat
from skills.demonstration import Demonstration
from skills.pose_dmp import PoseDMP
from skills.pose_model import PoseModel
from skills.state import PoseState
from skills.types import Array

#: Default smoothing of a recorded demonstration, s (the Gaussian's standard deviation):
#: its response is 0.9 at 2 Hz and 0.5 at 4.7 Hz, above a demonstrated arm motion's content
#: and below the noise that matters (0.5 mm of white noise in 100 Hz samples then leaves a
#: taught carry within 9 mm of its goal after its duration, against a metre unsmoothed).
DEFAULT_SMOOTHING_S = 0.04

#: The farthest a learnt skill may stray from its goal after the demonstration's duration,
#: m; beyond it the skill is not what was shown (:func:`reproduction`).
MAX_SETTLE_M = 0.02

#: The same for its orientation, deg.
MAX_SETTLE_DEG = 5.0

#: Most samples :func:`even_steps` interpolates a demonstration onto.
MAX_EVEN_SAMPLES = 20_000

#: The farthest a learnt skill may stray from its demonstration, RMS over its duration, as a
#: share of the demonstration's extent (its samples' farthest distance from its start), and
#: at least :data:`MIN_REPRODUCTION_M`: beyond it the skill is not the motion shown.
MAX_REPRODUCTION_SHARE = 0.1
MIN_REPRODUCTION_M = 0.005

#: Samples within this many standard deviations weigh in a smoothed one.
_REACH = 4.0
#: Stamps whose gaps all lie within this fraction of their median are even.
_EVEN_TOLERANCE = 1e-3
#: Most values (samples x window x dimensions) one block of smoothing holds: 32 MB of floats.
_BLOCK_VALUES = 1 << 22


def _gaussian_means(t: Array, values: Array, sigma: float) -> Array:
    """Each sample replaced by the Gaussian-weighted mean (``sigma`` s in time) of the samples
    near it, ``(N, D)``; beyond the ends the end samples stand in, repeated at the end steps
    (a demonstration starts and ends at rest: held there, not cut off)."""
    reach = _REACH * sigma
    step = float(np.median(np.diff(t)))  # the padding's, at the recording's usual rate
    count = int(np.ceil(reach / step))
    held = step * np.arange(1, count + 1)
    times = np.concatenate((t[0] - held[::-1], t, t[-1] + held))
    padded = np.concatenate(
        (np.repeat(values[:1], count, 0), values, np.repeat(values[-1:], count, 0))
    )
    # Unevenly stamped, each sample also weighs as the time it stands for (half the gaps to
    # its neighbours): a plain kernel mean leans towards where samples crowd (2.5 mm off a
    # curve the even stamps give within 0.5). Evenly stamped, every sample stands for the
    # same time: left as it was, bit for bit.
    gaps = np.diff(times)
    uneven = bool(np.max(np.abs(gaps - step)) > _EVEN_TOLERANCE * step)
    span = np.concatenate(([gaps[0]], 0.5 * (gaps[:-1] + gaps[1:]), [gaps[-1]]))
    lo = np.searchsorted(times, t - reach, side="left")
    hi = np.searchsorted(times, t + reach, side="right")
    # The samples' windows, block by block: (B, K) indices into the padded samples, K the
    # widest. A window holds rate x 8 sigma samples, so all N at once would take memory as the
    # rate squared (20000 samples over 3 s: 3 GB); a block holds about _BLOCK_VALUES values.
    width = np.arange(int(np.max(hi - lo)))
    rows = max(1, _BLOCK_VALUES // max(1, width.size * values.shape[1]))
    out = np.empty((t.size, values.shape[1]))
    for start in range(0, t.size, rows):
        block = slice(start, start + rows)
        index = lo[block, None] + width
        inside = index < hi[block, None]
        index = np.minimum(index, times.size - 1)
        weight = np.where(
            inside, np.exp(-0.5 * ((times[index] - t[block, None]) / sigma) ** 2), 0.0
        )
        if uneven:
            weight *= span[index]
        out[block] = np.einsum("nk,nkd->nd", weight, padded[index]) / weight.sum(axis=1)[:, None]
    return out


def even_steps(demo: Demonstration) -> tuple[Demonstration, str]:
    """``demo`` at even time steps, and what was done ('' when its stamps were even already:
    then it is returned as it is).

    Unevenly stamped samples (a tracker that dropped frames, a log written when it could) are
    interpolated onto steps of their median gap, at most :data:`MAX_EVEN_SAMPLES` of them:
    positions and the sign-continuous quaternions' components by a shape-preserving cubic
    (PCHIP: no overshoot between two samples, so close noisy stamps cannot swing it), the
    quaternions made unit again. Smoothed and differentiated as recorded, a 0.3 s dropout in
    a 3 s carry had put a kink in the accelerations the forcing is fitted to, and the taught
    skill strayed 0.4 m from its demonstration.
    """
    t = demo.t
    gaps = np.diff(t)
    step = float(np.median(gaps))
    if float(np.max(np.abs(gaps - step))) <= _EVEN_TOLERANCE * step:
        return demo, ""
    from scipy.interpolate import PchipInterpolator  # teaching only: not on a run's path

    n = min(MAX_EVEN_SAMPLES, round(float(t[-1] - t[0]) / step) + 1)
    times = np.linspace(t[0], t[-1], n)
    positions = PchipInterpolator(t, demo.positions, axis=0)(times)
    orientations = None
    if demo.orientations is not None:
        q = PchipInterpolator(t, quat.make_continuous(demo.orientations), axis=0)(times)
        orientations = q / np.linalg.norm(q, axis=1, keepdims=True)
    worst = int(np.argmax(gaps))
    note = (
        f"its time stamps were uneven (gaps {1000.0 * float(gaps.min()):.3g} to "
        f"{1000.0 * float(gaps[worst]):.3g} ms, the longest at {t[worst] - t[0]:.2f} s): "
        f"learnt from {n} samples interpolated at even {1000.0 * (times[1] - times[0]):.3g} ms "
        "steps"
    )
    return Demonstration.create(times, positions, orientations, demo.name), note


def low_pass(demo: Demonstration, sigma_s: float = DEFAULT_SMOOTHING_S) -> Demonstration:
    """``demo`` smoothed over ``sigma_s`` seconds (0: as it is): positions, and orientations
    as sign-continuous quaternions smoothed component-wise and made unit again (for the
    small turns between nearby samples, the same as smoothing the rotation).

    Raises
    ------
    ValueError
        On a negative or non-finite ``sigma_s``.
    """
    if not (np.isfinite(sigma_s) and sigma_s >= 0.0):
        raise ValueError(f"smoothing: expected a duration >= 0 s, got {sigma_s!r}")
    if sigma_s == 0.0:
        return demo
    d = demo.positions.shape[1]
    shown = (
        demo.positions
        if demo.orientations is None
        else np.hstack((demo.positions, demo.orientations))
    )
    smooth = _gaussian_means(demo.t, shown, sigma_s)  # one set of windows for both
    orientations = None
    if demo.orientations is not None:
        q = smooth[:, d:]
        orientations = q / np.linalg.norm(q, axis=1, keepdims=True)
    return Demonstration.create(demo.t, smooth[:, :d], orientations, demo.name)


#: The window at a recording's end over which :func:`end_speed` averages, s: at most this,
#: and at most :data:`END_WINDOW_SHARE` of the duration (a share alone had grown with rest
#: recorded before the motion, and taken its last deceleration for motion).
END_WINDOW_S = 0.1
#: The most of a short recording's duration that window takes.
END_WINDOW_SHARE = 0.05
#: A recording whose :func:`end_speed` is more than this share of its peak ends moving: cut
#: before the motion stopped (by that measure, smoothed, a carry of a cosine speed profile
#: ends at 0.12 of its peak, 0.16 with 2 mm of noise; one cut at its fastest at 0.6).
END_SPEED_SHARE = 0.25
#: Peaks below these are no motion to end, m/s and rad/s: a turn in place moves its position
#: by the tracker's noise alone (a peak of 6 mm/s), a carry may not turn at all.
MOTION_FLOOR = (0.02, 0.1)


def _end_start(t: Array) -> int:
    """Index of the first sample of :func:`end_speed`'s window (at least one step back)."""
    window = min(END_WINDOW_S, END_WINDOW_SHARE * float(t[-1] - t[0]))
    return min(int(np.searchsorted(t, t[-1] - window)), t.size - 2)


def end_speed(demo: Demonstration) -> tuple[float, float]:
    """The speed ``demo`` ends at and its peak speed, m/s: the end's the mean over its last
    :data:`END_WINDOW_S` (or :data:`END_WINDOW_SHARE` of a short one; the distance between
    the window's ends over its length, at least one step: a sample's own speed is its
    noise's); the peak its positions' finite differences (give it smoothed, :func:`low_pass`,
    or the noise is what they measure). A skill learnt from a recording cut before the
    motion stopped stops short of where it was going, or overshoots, as one learnt from noise
    strays from its goal."""
    speed = np.linalg.norm(demo.position_derivatives()[0], axis=1)
    t = demo.t
    start = _end_start(t)
    moved = float(np.linalg.norm(demo.positions[-1] - demo.positions[start]))
    return moved / float(t[-1] - t[start]), float(speed.max())


def end_turn_rate(demo: Demonstration) -> tuple[float, float]:
    """As :func:`end_speed`, for the orientation: the mean turn rate over the end's window
    (the angle between its end orientations over its length) and the peak, rad/s; (0, 0)
    without orientations."""
    if demo.orientations is None:
        return 0.0, 0.0
    rate = np.linalg.norm(demo.orientation_derivatives()[0], axis=1)
    t = demo.t
    start = _end_start(t)
    turned = float(quat.angle_between(demo.orientations[-1], demo.orientations[start]))
    return turned / float(t[-1] - t[start]), float(rate.max())


def ends_moving(demo: Demonstration) -> str:
    """How ``demo`` (smoothed) ends moving, its position or its turn at more than
    :data:`END_SPEED_SHARE` of its peak (:func:`end_speed`, :func:`end_turn_rate`; a peak
    under :data:`MOTION_FLOOR` is no motion), e.g. "moving at 0.145 m/s, its peak 0.239
    m/s"; "" when it ends at rest."""
    final, peak = end_speed(demo)
    if peak >= MOTION_FLOOR[0] and final > END_SPEED_SHARE * peak:
        return f"moving at {final:.3f} m/s, its peak {peak:.3f} m/s"
    final, peak = end_turn_rate(demo)
    if peak >= MOTION_FLOOR[1] and final > END_SPEED_SHARE * peak:
        return f"turning at {np.degrees(final):.1f} deg/s, its peak {np.degrees(peak):.1f} deg/s"
    return ""


#: A sample is still while its speed and turn rate are under this share of their peaks.
REST_SHARE = 0.05
#: Rest kept before a motion's first moving sample and after its last, s: the onset and the
#: settling, and the window :func:`ends_moving` reads at rest.
REST_KEPT_S = 0.15
#: Rest shorter than this in all is left as recorded, s.
REST_TRIMMED_S = 0.25


def trim_rest(demo: Demonstration, smoothed: Demonstration) -> tuple[Demonstration, float, float]:
    """``demo`` without the rest recorded before its motion and after it, and how long each
    was, s: a skill learnt with it waits that long at every use (a carry recorded from 2 s
    before the hand moved idled 2 s, and one stopped 5 s late lasted 7.5 s for 2.5 of
    motion). The motion runs from the first to the last sample of ``smoothed`` (``demo``
    smoothed, on the same stamps or ``demo``'s span) moving at :data:`REST_SHARE` or more of
    its peak speed or turn rate (a peak under :data:`MOTION_FLOOR` is no motion);
    :data:`REST_KEPT_S` of rest is kept at each end. A recording with less rest than
    :data:`REST_TRIMMED_S` in all, or no motion, is returned as it is, with (0, 0)."""
    t = smoothed.t
    moving = np.zeros(t.size, dtype=bool)
    speed = np.linalg.norm(smoothed.position_derivatives()[0], axis=1)
    if speed.max() >= MOTION_FLOOR[0]:
        moving |= speed >= REST_SHARE * speed.max()
    if smoothed.orientations is not None:
        rate = np.linalg.norm(smoothed.orientation_derivatives()[0], axis=1)
        if rate.max() >= MOTION_FLOOR[1]:
            moving |= rate >= REST_SHARE * rate.max()
    if not moving.any():
        return demo, 0.0, 0.0
    begin = max(float(t[np.argmax(moving)]) - REST_KEPT_S, float(demo.t[0]))
    end = min(float(t[t.size - 1 - np.argmax(moving[::-1])]) + REST_KEPT_S, float(demo.t[-1]))
    before, after = begin - float(demo.t[0]), float(demo.t[-1]) - end
    keep = (demo.t >= begin - 1e-9) & (demo.t <= end + 1e-9)
    if before + after < REST_TRIMMED_S or keep.sum() < 3:
        return demo, 0.0, 0.0
    orientations = None if demo.orientations is None else demo.orientations[keep]
    trimmed = Demonstration.create(demo.t[keep], demo.positions[keep], orientations, demo.name)
    return trimmed, before, after


@dataclass(frozen=True)
class Reproduction:
    """How a learnt skill, rolled out from its demonstration's start to its goal, compares.

    Attributes
    ----------
    rms_m : float
        RMS distance from the demonstrated positions over its duration, m.
    settle_m : float
        Farthest distance from the goal after its duration (to 1.5 times it), m.
    settle_deg : float
        Farthest turn from the goal orientation after its duration, deg (0 without one).
    """

    rms_m: float
    settle_m: float
    settle_deg: float
    #: The demonstration's extent: its samples' farthest distance from its start, m.
    extent_m: float = 0.0

    @property
    def settles(self) -> bool:
        """It stays within :data:`MAX_SETTLE_M` and :data:`MAX_SETTLE_DEG` of its goal."""
        return self.settle_m <= MAX_SETTLE_M and self.settle_deg <= MAX_SETTLE_DEG

    @property
    def allowed_rms_m(self) -> float:
        """The most :attr:`rms_m` a skill may have (:data:`MAX_REPRODUCTION_SHARE`)."""
        return max(MIN_REPRODUCTION_M, MAX_REPRODUCTION_SHARE * self.extent_m)

    @property
    def follows(self) -> bool:
        """It follows its demonstration within :attr:`allowed_rms_m`."""
        return self.rms_m <= self.allowed_rms_m


def reproduction(model: PoseModel, demo: Demonstration, dt: float = 1.0 / 120.0) -> Reproduction:
    """Roll ``model`` out from ``demo``'s first pose to its last over its duration, and on to
    1.5 times it, in steps of ``dt`` s; compare (:class:`Reproduction`)."""
    tau = demo.duration
    q = demo.orientations
    q0 = quat.IDENTITY if q is None else q[0]
    goal_q = quat.IDENTITY if q is None else q[-1]
    goal = demo.positions[-1]
    dmp = PoseDMP.start(
        model, PoseState.at_rest(demo.positions[0], q0), goal, goal_q, tau, blend_fraction=0.0
    )
    path = dmp.rollout(dt, int(np.ceil(1.5 * tau / dt)))
    times, positions = path.t, path.positions
    during = times <= tau
    shown = np.column_stack(
        [np.interp(times[during], demo.t - demo.t[0], demo.positions[:, k]) for k in range(3)]
    )
    rms = float(np.sqrt(np.mean(np.sum((positions[during] - shown) ** 2, axis=1))))
    after = ~during
    settle_m = float(np.max(np.linalg.norm(positions[after] - goal, axis=1), initial=0.0))
    settle_deg = 0.0
    if q is not None and after.any():
        turned = quat.angle_between(path.orientations[after], goal_q)
        settle_deg = float(np.degrees(np.max(turned)))
    extent = float(np.max(np.linalg.norm(demo.positions - demo.positions[0], axis=1)))
    return Reproduction(rms, settle_m, settle_deg, extent)


__all__ = [
    "DEFAULT_SMOOTHING_S",
    "END_SPEED_SHARE",
    "END_WINDOW_S",
    "END_WINDOW_SHARE",
    "MAX_EVEN_SAMPLES",
    "MAX_REPRODUCTION_SHARE",
    "MAX_SETTLE_DEG",
    "MAX_SETTLE_M",
    "MIN_REPRODUCTION_M",
    "MOTION_FLOOR",
    "REST_KEPT_S",
    "REST_SHARE",
    "REST_TRIMMED_S",
    "Reproduction",
    "end_speed",
    "end_turn_rate",
    "ends_moving",
    "even_steps",
    "low_pass",
    "reproduction",
    "trim_rest",
]
