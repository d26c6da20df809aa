"""How well a run carried its objects, beside whether it succeeded (issue 16, as RoboEval does).

Pure numpy over arrays the episode's recorder samples once per control step
(:class:`GripSamples`, one per object); nothing here reads the simulation. An object is *held*
at a sample when both palms press on it with at least the tree's ``min_force_n`` (the IsHeld
and Transport leaves' test); a *grasp* is a run of held samples, and each starts at a rising
edge of held. Every peak below is taken over held samples only, except the squeeze (any time).
A metric with no held sample to measure is NaN (``None`` in a record).
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass, fields

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view
from numpy.typing import ArrayLike, NDArray

from skills import quaternion as quat
from skills.dual_arm import shift_along_face
from skills.types import Array

#: A boolean array, one flag per sample.
Mask = NDArray[np.bool_]

#: Shortest dip of the palms' force below the threshold that ends a grasp, s: a palm that
#: slides or bounces for a control step or two has not let go.
GRASP_GAP_S = 0.1

#: Samples in the centred moving average of the object's velocity before it is differenced
#: twice for jerk (odd; 5 at 60 Hz spans 83 ms, its first zero at 12 Hz).
JERK_WINDOW = 5


#: Each sampled array's shape after its leading T.
_SAMPLE_SHAPES: dict[str, tuple[int, ...]] = {
    "object_positions": (3,),
    "object_orientations": (4,),
    "object_velocities": (3,),
    "object_angular_velocities": (3,),
    "palm_positions": (2, 3),
    "palm_velocities": (2, 3),
    "palm_forces": (2,),
}


@dataclass(frozen=True)
class GripSamples:
    """One object and both palms, sampled every control step (T samples), world frame.

    Attributes
    ----------
    object_positions : (T, 3) float
        The object's centre, m.
    object_orientations : (T, 4) float
        The object's orientation, scalar-last unit quaternions.
    object_velocities : (T, 3) float
        The object centre's linear velocity, m/s.
    object_angular_velocities : (T, 3) float
        The object's angular velocity, rad/s.
    palm_positions : (T, 2, 3) float
        Each palm's frame origin (left, right), m.
    palm_velocities : (T, 2, 3) float
        Each palm's linear velocity (left, right), m/s.
    palm_forces : (T, 2) float
        Each palm's summed contact normal force on this object (left, right), N.
    dt : float
        Time between samples (the control period), s.
    """

    object_positions: Array
    object_orientations: Array
    object_velocities: Array
    object_angular_velocities: Array
    palm_positions: Array
    palm_velocities: Array
    palm_forces: Array
    dt: float

    def __post_init__(self) -> None:
        n = np.shape(self.palm_forces)[0] if np.ndim(self.palm_forces) else -1
        for name, tail in _SAMPLE_SHAPES.items():
            value = np.asarray(getattr(self, name), dtype=float)
            if value.shape != (n, *tail):
                raise ValueError(
                    f"GripSamples: expected {name} of shape {('T', *tail)} with T={n} "
                    f"(palm_forces' length), got {value.shape}"
                )
            object.__setattr__(self, name, value)
        if not self.dt > 0.0:
            raise ValueError(f"GripSamples: expected dt > 0 s, got {self.dt}")

    @classmethod
    def empty(cls, dt: float) -> GripSamples:
        """No samples (a run that never ticked)."""
        return cls(**{k: np.zeros((0, *t)) for k, t in _SAMPLE_SHAPES.items()}, dt=dt)


@dataclass(frozen=True)
class GripMetrics:
    """A run's behavioural metrics; a float is NaN when there was nothing to measure."""

    #: Largest displacement of a palm in the object's frame from where it was when the grasp
    #: began (the first held sample), mm; the squeeze settling in after that counts too.
    slip_mm: float = math.nan
    #: Largest angle between the held object's z axis and world z, degrees.
    peak_tilt_deg: float = math.nan
    #: Largest departure of the palms' relative velocity from a rigid grasp's, m/s.
    palm_velocity_mismatch_mps: float = math.nan
    #: Largest norm of the held object's jerk, m/s^3.
    peak_jerk_mps3: float = math.nan
    #: Largest palm normal force on an object at any time, N.
    peak_squeeze_n: float = math.nan
    #: Grasps made (rising edges of held), over all objects.
    contact_count: int = 0
    #: Grasps of an object after its first, summed over objects.
    regrasp_count: int = 0

    def summary(self) -> dict[str, float | int | None]:
        """JSON-ready values, rounded below what the physics resolves; NaN as None."""
        digits = {
            "slip_mm": 3,
            "peak_tilt_deg": 3,
            "palm_velocity_mismatch_mps": 4,
            "peak_jerk_mps3": 2,
            "peak_squeeze_n": 2,
        }
        out: dict[str, float | int | None] = {}
        for name, places in digits.items():
            value = float(getattr(self, name))
            out[name] = None if math.isnan(value) else round(value, places)
        out["contact_count"] = self.contact_count
        out["regrasp_count"] = self.regrasp_count
        return out


#: The metrics a record carries, in the order tables list them, with their table labels.
METRIC_LABELS: dict[str, str] = {
    "slip_mm": "slip in the grip, mm",
    "peak_tilt_deg": "peak tilt while held, deg",
    "palm_velocity_mismatch_mps": "palm velocity mismatch, m/s",
    "peak_jerk_mps3": "peak jerk while held, m/s^3",
    "peak_squeeze_n": "peak squeeze, N",
    "contact_count": "grasps made",
    "regrasp_count": "re-grasps",
}
METRIC_NAMES = tuple(f.name for f in fields(GripMetrics))


def held_mask(palm_forces: ArrayLike, min_force_n: float, bridge: int = 0) -> Mask:
    """Whether both palms press with at least ``min_force_n`` N, (T,) bool, from forces (T, 2) N.

    A dip below the threshold shorter than ``bridge`` samples between two held samples (a palm
    sliding or bouncing for a step or two) does not end the grasp: it counts as held.
    """
    held = np.asarray(palm_forces, dtype=float).min(axis=-1) >= min_force_n
    on = np.flatnonzero(held)
    gaps = np.flatnonzero((np.diff(on) > 1) & (np.diff(on) <= bridge))
    if gaps.size:
        # +1 where a short gap opens, -1 where it closes: its samples sum to 1.
        edges = np.zeros(held.shape[0] + 1, dtype=np.int_)
        np.add.at(edges, on[gaps] + 1, 1)
        np.add.at(edges, on[gaps + 1], -1)
        held |= np.cumsum(edges)[:-1] > 0
    return held


def grasp_starts(held: ArrayLike) -> Mask:
    """Rising edges of ``held`` (T,): the samples where a grasp begins, (T,) bool (a run that
    starts held begins a grasp at sample 0)."""
    h = np.asarray(held, dtype=bool)
    return h & ~np.concatenate(([False], h[:-1]))


def grasp_index(held: ArrayLike) -> NDArray[np.int_]:
    """Which grasp each sample belongs to, from 0 in order, -1 where not held; (T,) int."""
    h = np.asarray(held, dtype=bool)
    return np.where(h, np.cumsum(grasp_starts(h)) - 1, -1)


def _peak(values: Array, where: Mask | None = None) -> float:
    """Largest of ``values`` (T,) where ``where`` (T,) holds (default: where finite); NaN if
    nowhere."""
    chosen = values[np.isfinite(values) if where is None else where]
    return float(chosen.max()) if chosen.size else math.nan


def palm2object_positions(
    palm_positions: ArrayLike, object_positions: ArrayLike, object_orientations: ArrayLike
) -> Array:
    """Palm positions (T, 2, 3) m, world frame, in the object's frame (T, 2, 3) m."""
    offset = np.asarray(palm_positions, dtype=float) - np.asarray(object_positions)[:, None]
    return quat.rotate(quat.conjugate(np.asarray(object_orientations))[:, None], offset)


def slip_m(
    palm_positions: ArrayLike,
    object_positions: ArrayLike,
    object_orientations: ArrayLike,
    held: ArrayLike,
) -> float:
    """Largest slip in the grip, m: over held samples and both palms, how far the palm's
    position in the object's frame has moved along the face from its value at the first sample
    of that grasp. Motion along the palm's line to the object's centre (the squeeze settling
    in, a palm pressing deeper) is not slip and is left out.

    Parameters
    ----------
    palm_positions : (T, 2, 3) m, world frame
    object_positions : (T, 3) m, world frame
    object_orientations : (T, 4) scalar-last quaternions
    held : (T,) bool
        A new grasp (rising edge) takes a new reference.
    """
    h = np.asarray(held, dtype=bool)
    local = palm2object_positions(palm_positions, object_positions, object_orientations)
    reference = local[np.flatnonzero(grasp_starts(h))][grasp_index(h)[h]]  # (held, 2, 3)
    return _peak(shift_along_face(local[h], reference).ravel())


def peak_tilt_rad(object_orientations: ArrayLike, held: ArrayLike) -> float:
    """Largest tilt of the held object from upright (:func:`skills.quaternion.tilt`), rad, from
    orientations (T, 4) and ``held`` (T,)."""
    return _peak(quat.tilt(np.asarray(object_orientations, dtype=float)), np.asarray(held, bool))


def palm_velocity_mismatch_mps(
    palm_positions: ArrayLike,
    palm_velocities: ArrayLike,
    object_angular_velocities: ArrayLike,
    held: ArrayLike,
) -> float:
    """Largest departure of the palms' relative velocity from a rigid grasp's, m/s.

    Two points fixed on one rigid body moving with angular velocity omega have
    ``v_L - v_R = omega x (p_L - p_R)``; the mismatch at a sample is
    ``|(v_L - v_R) - omega_object x (p_L - p_R)|``, with omega the object's measured angular
    velocity: zero while the palms move as if bolted to the object, whatever it does, and the
    rate at which they squeeze, shear or twist against each other otherwise.

    Parameters
    ----------
    palm_positions : (T, 2, 3) m, world frame (left, right)
    palm_velocities : (T, 2, 3) m/s, world frame (left, right)
    object_angular_velocities : (T, 3) rad/s, world frame
    held : (T,) bool
    """
    p = np.asarray(palm_positions, dtype=float)
    v = np.asarray(palm_velocities, dtype=float)
    rigid = np.cross(np.asarray(object_angular_velocities, dtype=float), p[:, 0] - p[:, 1])
    mismatch = np.linalg.norm(v[:, 0] - v[:, 1] - rigid, axis=-1)
    return _peak(mismatch, np.asarray(held, dtype=bool))


def jerk_norms(
    velocities: ArrayLike, dt: float, held: ArrayLike, window: int = JERK_WINDOW
) -> Array:
    """The held object's jerk norm per sample, m/s^3, (T,), NaN where it is not measured.

    The velocity (T, 3) m/s is smoothed by a centred moving average of ``window`` samples,
    then differenced twice (central second difference over ``dt``); a sample gets a value only
    when every sample its ``window + 2`` stencil reads is held within one grasp, so neither
    grasping nor letting go counts. The average has weights summing to one and is symmetric,
    so a quadratic velocity (cubic position) keeps its exact second difference. Deterministic:
    plain sums over fixed windows, no state carried between runs.

    Parameters
    ----------
    velocities : (T, 3) m/s, world frame
        The object centre's measured velocity, one sample per control step.
    dt : float
        Time between samples, s.
    held : (T,) bool
    window : int
        Samples averaged, odd (:data:`JERK_WINDOW`).
    """
    if window < 1 or window % 2 == 0:
        raise ValueError(f"jerk_norms: expected an odd window >= 1, got {window}")
    v = np.asarray(velocities, dtype=float)
    g = grasp_index(held)
    out = np.full(v.shape[0], math.nan)
    span = window + 2
    if v.shape[0] < span:
        return out
    smooth = sliding_window_view(v, window, axis=0).mean(axis=-1)  # (T - window + 1, 3)
    jerk = (smooth[2:] - 2.0 * smooth[1:-1] + smooth[:-2]) / (dt * dt)  # (T - span + 1, 3)
    stencil = sliding_window_view(g, span)
    inside = (stencil.min(axis=-1) == stencil.max(axis=-1)) & (stencil[:, 0] >= 0)
    centre = span // 2
    out[centre : centre + jerk.shape[0]] = np.where(inside, np.linalg.norm(jerk, axis=-1), math.nan)
    return out


def grip_metrics(samples: GripSamples, min_force_n: float) -> GripMetrics:
    """Every metric of one object's samples (held: :func:`held_mask` with ``min_force_n`` N)."""
    s = samples
    held = held_mask(s.palm_forces, min_force_n, bridge=math.ceil(GRASP_GAP_S / s.dt - 1e-9))
    contacts = int(grasp_starts(held).sum())
    return GripMetrics(
        slip_mm=1000.0 * slip_m(s.palm_positions, s.object_positions, s.object_orientations, held),
        peak_tilt_deg=math.degrees(peak_tilt_rad(s.object_orientations, held)),
        palm_velocity_mismatch_mps=palm_velocity_mismatch_mps(
            s.palm_positions, s.palm_velocities, s.object_angular_velocities, held
        ),
        peak_jerk_mps3=_peak(jerk_norms(s.object_velocities, s.dt, held)),
        peak_squeeze_n=_peak(s.palm_forces.ravel()),
        contact_count=contacts,
        regrasp_count=max(contacts - 1, 0),
    )


def worst(metrics: Iterable[GripMetrics]) -> GripMetrics:
    """A run's metrics from its objects': the largest of each peak (NaN only if every object's
    is), the grasps and re-grasps summed."""
    ms = list(metrics)

    def top(name: str) -> float:
        values = [float(getattr(m, name)) for m in ms if not math.isnan(getattr(m, name))]
        return max(values) if values else math.nan

    return GripMetrics(
        **{n: top(n) for n in METRIC_NAMES if n not in ("contact_count", "regrasp_count")},
        contact_count=sum(m.contact_count for m in ms),
        regrasp_count=sum(m.regrasp_count for m in ms),
    )
