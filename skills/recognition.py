"""Movement recognition: which library skill a new demonstration is, if any.

As in the paper (after Ijspeert et al. 2002), a demonstration is compared with the skills in
the library and added as a new skill when it matches none. The comparison is between motion
*signatures*, which make it independent of where, how far, which way round the vertical and
how fast a motion went:

- time is normalised to ``[0, 1]`` and the motion resampled at ``n`` points;
- positions are taken from the start and expressed in a frame whose x axis is the horizontal
  start-to-goal direction (z stays up); orientations are rotation vectors from the start;
- each is smoothed over 1 % of the motion (sensor noise that differentiation would amplify;
  anything slower than about 16 cycles per motion is kept) and differentiated: the signature
  is the *velocity profile* per axis, linear and angular, each divided by its peak speed;
- the signature is normalised to unit length, and similarity is the cosine of two signatures
  (1 the same shape, 0 unrelated, -1 reversed).

Why velocities: a position profile is dominated by the start-to-goal displacement, so a carry
with a 3 cm wave on it still scored 0.997 against the plain carry; the wave's velocity is as
large as the carry's, and its profile scores 0.89 (``tests/skills/test_recognition.py``).

The threshold: write a demonstration's signature as the skill's plus a deviation ``e``; its
cosine is ``1 / sqrt(1 + |e|^2)`` for a deviation orthogonal to the skill. A human repeat of a
skill (hand tremor, another place, speed and size) deviates by about 5 % RMS (cosine 0.998);
:data:`DEFAULT_THRESHOLD` = 0.98 accepts up to 20 % (``1 / sqrt(1.04)``), four times that,
and rejects a different shape laid over the same carry.

For a learnt skill the signature is that of its DMP reproducing its own demonstration.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np
from scipy.ndimage import gaussian_filter1d

from skills import quaternion as quat
from skills.demonstration import Demonstration
from skills.library import SkillLibrary
from skills.pose_dmp import PoseState, pose_rollout
from skills.skill import Skill, SkillKind
from skills.types import Array
from skills.vocabulary import Space

#: Cosine above which a demonstration is an existing skill (derivation in the module's text).
DEFAULT_THRESHOLD = 0.98
#: Smoothing before differentiation, as a share of the motion's duration.
_SMOOTHING = 0.01
_MIN_EXTENT_M = 0.01
_MIN_ANGLE_RAD = 0.05


def signature(t: Array, positions: Array, orientations: Array, n: int = 100) -> Array:
    """Normalised velocity-profile signature, shape (n * 6,), unit norm (zeros for no motion).

    Parameters
    ----------
    t : ndarray, shape (N,)
    positions : ndarray, shape (N, 3)
    orientations : ndarray, shape (N, 4)
    n : int
        Resampling points.
    """
    u = (t - t[0]) / (t[-1] - t[0])
    grid = np.linspace(0.0, 1.0, n)
    rel = positions - positions[0]
    horizontal = rel[-1, :2]
    norm_h = float(np.hypot(*horizontal))
    if norm_h > _MIN_EXTENT_M:
        c, s = horizontal / norm_h
        rel = np.stack(
            (c * rel[:, 0] + s * rel[:, 1], -s * rel[:, 0] + c * rel[:, 1], rel[:, 2]), axis=1
        )
    q = quat.make_continuous(orientations)
    rot = 2.0 * quat.log(quat.canonical(quat.multiply(q, quat.conjugate(q[0]))))
    blocks = [_velocity_profile(grid, u, rel, _MIN_EXTENT_M, n)]
    blocks.append(_velocity_profile(grid, u, rot, _MIN_ANGLE_RAD, n))
    flat = np.concatenate(blocks, axis=1).ravel()
    norm = float(np.linalg.norm(flat))
    return flat / norm if norm > 0 else flat


def _velocity_profile(grid: Array, u: Array, values: Array, floor: float, n: int) -> Array:
    """(n, 3) rate of ``values`` (N, 3) over normalised time, over its peak; zeros if it moves
    less than ``floor`` (m or rad) from its start."""
    resampled = np.stack([np.interp(grid, u, values[:, k]) for k in range(3)], axis=1)
    if float(np.max(np.linalg.norm(resampled, axis=1))) <= floor:
        return np.zeros_like(resampled)
    smooth = gaussian_filter1d(resampled, _SMOOTHING * n, axis=0, mode="nearest")
    rate = np.gradient(smooth, grid, axis=0)
    peak = float(np.max(np.linalg.norm(rate, axis=1)))
    return rate / peak if peak > 0 else np.zeros_like(rate)


def demo_signature(demo: Demonstration, n: int = 100) -> Array:
    """Signature of a demonstration (orientations default to identity)."""
    q = demo.orientations
    if q is None:
        q = np.tile(quat.IDENTITY, (demo.n_samples, 1))
    return signature(demo.t, demo.positions, q, n)


def skill_signature(skill: Skill, n: int = 100, steps: int = 400) -> Array:
    """Signature of a learnt skill reproducing its own demonstration."""
    model = skill.pose_model()
    start = PoseState.at_rest(model.position.demo_start, model.orientation.demo_start)
    target = model.target(
        start.position, start.orientation, model.position.demo_goal, model.orientation.demo_goal
    )
    dt = model.demo_tau / steps
    traj = pose_rollout(model, target, start, dt, steps)
    return signature(traj.t, traj.positions, traj.orientations, n)


@dataclass(frozen=True)
class Recognition:
    """Outcome of comparing a demonstration with a library.

    Attributes
    ----------
    best : str or None
        Name of the most similar learnt skill (None if the library has none to compare).
    similarity : float
        Its cosine similarity in [-1, 1].
    matched : bool
        ``similarity >= threshold``.
    scores : Mapping[str, float]
        Similarity to every compared skill.
    threshold : float
    """

    best: str | None
    similarity: float
    matched: bool
    scores: Mapping[str, float] = field(default_factory=dict)
    threshold: float = DEFAULT_THRESHOLD


def recognise(
    library: SkillLibrary,
    demo: Demonstration,
    space: Space | None = None,
    threshold: float = DEFAULT_THRESHOLD,
) -> Recognition:
    """Compare ``demo`` with every learnt skill (in ``space`` if given)."""
    if not -1.0 <= threshold <= 1.0:
        raise ValueError(f"threshold: expected a cosine similarity in [-1, 1], got {threshold!r}")
    sig = demo_signature(demo)
    scores = {
        s.name: float(np.dot(sig, skill_signature(s)))
        for s in library
        if s.kind is SkillKind.LEARNT_DMP and (space is None or s.space is space)
    }
    if not scores:
        return Recognition(None, 0.0, False, scores, threshold)
    best = max(scores, key=lambda k: scores[k])
    return Recognition(best, scores[best], scores[best] >= threshold, scores, threshold)
