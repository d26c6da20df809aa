"""Movement recognition: which library skill a new demonstration is, if any.

As in the paper (after Ijspeert et al. 2002), a demonstration is compared with the skills in
the library and added as a new skill when it matches none. The comparison is between motion
*signatures*, which make the comparison independent of where, how far, which way round the
vertical and how fast a motion went:

- time is normalised to ``[0, 1]`` and resampled at ``n`` points;
- positions are taken from the start and expressed in a frame whose x axis is the horizontal
  start-to-goal direction (z stays up), then divided by the path's largest extent;
- orientations are rotation vectors from the start orientation, divided by their largest angle;
- the signature is normalised to unit length, and similarity is the cosine of two signatures
  (1 the same shape, 0 unrelated, -1 reversed).

For a learnt skill the signature is that of its DMP reproducing its own demonstration.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from skills import quaternion as quat
from skills.demonstration import Demonstration
from skills.library import SkillLibrary
from skills.pose_dmp import PoseState, pose_rollout
from skills.skill import Skill, SkillKind
from skills.types import Array
from skills.vocabulary import Space

DEFAULT_THRESHOLD = 0.9
_MIN_EXTENT_M = 0.01
_MIN_ANGLE_RAD = 0.05


def signature(t: Array, positions: Array, orientations: Array, n: int = 100) -> Array:
    """Normalised motion signature, shape (n * 6,), unit norm (or zeros for no motion).

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
    extent = float(np.max(np.linalg.norm(rel, axis=1)))
    pos_sig = rel / extent if extent > _MIN_EXTENT_M else np.zeros_like(rel)
    q = quat.make_continuous(orientations)
    rot = 2.0 * quat.log(quat.canonical(quat.multiply(q, quat.conjugate(q[0]))))
    angle = float(np.max(np.linalg.norm(rot, axis=1)))
    rot_sig = rot / angle if angle > _MIN_ANGLE_RAD else np.zeros_like(rot)
    both = np.concatenate((pos_sig, rot_sig), axis=1)
    resampled = np.stack([np.interp(grid, u, both[:, k]) for k in range(6)], axis=1)
    flat = resampled.ravel()
    norm = float(np.linalg.norm(flat))
    return flat / norm if norm > 0 else flat


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
