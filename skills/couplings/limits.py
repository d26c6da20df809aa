"""Workspace and joint-limit repulsion (after Gams et al. 2009).

Both use the same barrier per coordinate: with ``d`` the distance to a limit and ``m`` the
margin, the push away from that limit is

    a(d) = k (1/d - 1/m)    for d < m, else 0

zero and continuous at the margin, growing as the limit nears; ``d`` is clipped below at
``min_distance`` so it stays finite at (and beyond) the limit, where it is strongest. The two
limits of a coordinate add with opposite signs, so a box narrower than twice the margin is
pushed towards its middle, symmetrically.

:class:`JointLimitRepulsion` computes the barrier in joint space and maps it to the task space
of the point the DMP drives through that point's Jacobian: ``a_task = J(q) qdd_rep``, the
task acceleration the repulsive joint acceleration would produce (``Jdot qd`` neglected). No
pseudo-inverse is needed in this direction. The robot's controller resolves the DMP's
acceleration back through its damped least-squares inverse ``J^T (J J^T + l^2 I)^-1``, which
turns ``J qdd_rep`` into the part of ``qdd_rep`` in the row space of ``J`` (attenuated slightly
by ``l``): the part a task-space coupling can realise. The null-space part is the controller's
posture task's job, not the DMP's.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from skills.couplings._checks import ZERO3, assign, positive, vector
from skills.kernel import kernel
from skills.program import Kind, Packer
from skills.state import PoseState, PoseTarget
from skills.types import Array


def barrier(
    lower_distance: Array, upper_distance: Array, gain: float, margin: Array, min_distance: Array
) -> Array:
    """Net push ``a(d_lower) - a(d_upper)`` per coordinate (positive away from the lower limit).

    Parameters
    ----------
    lower_distance, upper_distance : ndarray, shape (n,)
        ``x - lower`` and ``upper - x``, negative beyond a limit.
    gain : float
        ``k``, in the coordinate's unit squared per s^2.
    margin, min_distance : ndarray, shape (n,) or scalar
        Where the push starts, and the clipping distance.
    """
    inv_m = 1.0 / margin
    lo = np.maximum(1.0 / np.maximum(lower_distance, min_distance) - inv_m, 0.0)
    hi = np.maximum(1.0 / np.maximum(upper_distance, min_distance) - inv_m, 0.0)
    out: Array = gain * (lo - hi)
    return out


def _limits(lower: ArrayLike, upper: ArrayLike, shape: tuple[int]) -> tuple[Array, Array]:
    lo = vector(lower, shape, "lower")
    hi = vector(upper, shape, "upper")
    if lo.shape != hi.shape:
        raise ValueError(f"upper: expected shape {lo.shape} like lower, got {hi.shape}")
    bad = np.flatnonzero(hi <= lo)
    if bad.size:
        i = int(bad[0])
        raise ValueError(
            f"upper: expected upper > lower, got upper[{i}]={hi[i]} <= lower[{i}]={lo[i]}"
        )
    return lo, hi


def _margins(margin: ArrayLike, min_distance: float | None, n: int) -> tuple[Array, Array]:
    m = np.broadcast_to(np.asarray(margin, dtype=float), (n,)).copy()
    if not np.all(np.isfinite(m) & (m > 0.0)):
        raise ValueError(f"margin: expected distances > 0, got {margin!r}")
    if min_distance is None:
        md = m / 100.0
    else:
        md = np.full(n, positive(min_distance, "min_distance"))
        if np.any(md >= m):
            raise ValueError(f"min_distance: expected less than the margin, got {min_distance!r}")
    m.setflags(write=False)
    md.setflags(write=False)
    return m, md


@dataclass(frozen=True, eq=False, init=False)
class WorkspaceRepulsion:
    """Keeps the DMP's position inside an axis-aligned box (a :class:`CouplingTerm`).

    Parameters
    ----------
    lower, upper : array_like, shape (3,)
        Box corners in the DMP's frame, m (``upper > lower``).
    margin : float or array_like, shape (3,)
        Distance from a face where the push starts, m (> 0).
    gain : float
        ``k``, m^2/s^2 (> 0): the push is ``k (1/d - 1/margin)`` m/s^2.
    min_distance : float, optional
        Clipping distance, m; default margin / 100.
    """

    lower: Array
    upper: Array
    margin: Array
    gain: float
    min_distance: float | None
    _clip: Array = field(init=False, repr=False)

    def __init__(
        self,
        lower: ArrayLike,
        upper: ArrayLike,
        margin: ArrayLike = 0.05,
        gain: float = 0.05,
        min_distance: float | None = None,
    ) -> None:
        assign(self, lower=lower, upper=upper, margin=margin, gain=gain, min_distance=min_distance)
        self.__post_init__()

    def __post_init__(self) -> None:
        lo, hi = _limits(self.lower, self.upper, (3,))
        m, md = _margins(self.margin, self.min_distance, 3)
        set_ = object.__setattr__
        set_(self, "lower", lo)
        set_(self, "upper", hi)
        set_(self, "margin", m)
        set_(self, "gain", positive(self.gain, "gain"))
        set_(self, "_clip", md)

    def acceleration(self, state: PoseState, target: PoseTarget) -> tuple[Array, Array]:
        """Repulsion from the faces, m/s^2 (zero beyond the margin); angular part zero."""
        y = state.position
        return barrier(
            y - self.lower, self.upper - y, self.gain, self.margin, self._clip
        ), ZERO3.copy()

    def pack(self, packer: Packer, weight: float) -> None:
        """A WORKSPACE block: ``[w, lower (3), upper (3), margin (3), clip (3), gain]``."""
        packer.add(
            Kind.WORKSPACE,
            [
                weight,
                *self.lower.tolist(),
                *self.upper.tolist(),
                *self.margin.tolist(),
                *self._clip.tolist(),
                self.gain,
            ],
        )


@kernel
def workspace_kernel(x: Array, b: int, data: Array, o: int, a: Array) -> None:
    """:meth:`WorkspaceRepulsion.acceleration` (the :func:`barrier` per axis) of the state at
    ``x[b:]`` from its block at ``data[o:]``, into ``a`` (6)."""
    gain = data[o + 13]
    a[:] = 0.0
    for i in range(3):
        y = x[b + i]
        inv_m = 1.0 / data[o + 7 + i]
        clip = data[o + 10 + i]
        lo = max(1.0 / max(y - data[o + 1 + i], clip) - inv_m, 0.0)
        hi = max(1.0 / max(data[o + 4 + i] - y, clip) - inv_m, 0.0)
        a[i] = gain * (lo - hi)


@dataclass(frozen=True, eq=False, init=False)
class JointLimitRepulsion:
    """Keeps the arm's joints off their limits by pushing the point the DMP drives.

    Parameters
    ----------
    joint_positions : callable
        ``() -> ndarray (n,)``, rad (or m for prismatic joints), read once per tick.
    jacobian : callable
        ``() -> ndarray (6, n)``: the task Jacobian of the driven point at the current joints,
        linear rows first, in the DMP's frame.
    lower, upper : array_like, shape (n,)
        Joint limits (``upper > lower``).
    margin : float or array_like, shape (n,)
        Distance from a limit where the push starts, rad (> 0).
    gain : float
        ``k``, rad^2/s^2 (> 0): the joint push is ``k (1/d - 1/margin)`` rad/s^2.
    min_distance : float, optional
        Clipping distance, rad; default margin / 100.
    """

    joint_positions: Callable[[], Array]
    jacobian: Callable[[], Array]
    lower: Array
    upper: Array
    margin: Array
    gain: float
    min_distance: float | None
    _clip: Array = field(init=False, repr=False)

    def __init__(
        self,
        joint_positions: Callable[[], Array],
        jacobian: Callable[[], Array],
        lower: ArrayLike,
        upper: ArrayLike,
        margin: ArrayLike = 0.2,
        gain: float = 0.1,
        min_distance: float | None = None,
    ) -> None:
        assign(
            self,
            joint_positions=joint_positions,
            jacobian=jacobian,
            lower=lower,
            upper=upper,
            margin=margin,
            gain=gain,
            min_distance=min_distance,
        )
        self.__post_init__()

    def __post_init__(self) -> None:
        lo, hi = _limits(self.lower, self.upper, (-1,))
        m, md = _margins(self.margin, self.min_distance, lo.shape[0])
        if not (callable(self.joint_positions) and callable(self.jacobian)):
            raise ValueError("joint_positions, jacobian: expected callables, got a non-callable")
        set_ = object.__setattr__
        set_(self, "lower", lo)
        set_(self, "upper", hi)
        set_(self, "margin", m)
        set_(self, "gain", positive(self.gain, "gain"))
        set_(self, "_clip", md)

    def joint_acceleration(self) -> Array:
        """The repulsive joint acceleration ``qdd_rep``, shape (n,), at the current joints."""
        q = np.asarray(self.joint_positions(), dtype=float)
        n = self.lower.shape[0]
        if q.shape != (n,):
            raise ValueError(f"joint_positions: expected shape ({n},), got {q.shape}")
        return barrier(q - self.lower, self.upper - q, self.gain, self.margin, self._clip)

    def acceleration(self, state: PoseState, target: PoseTarget) -> tuple[Array, Array]:
        """``J qdd_rep``: linear m/s^2 and angular rad/s^2 of the driven point, (3,) each."""
        qdd = self.joint_acceleration()
        if not qdd.any():
            return ZERO3.copy(), ZERO3.copy()
        jac = np.asarray(self.jacobian(), dtype=float)
        if jac.shape != (6, qdd.shape[0]):
            raise ValueError(f"jacobian: expected shape (6, {qdd.shape[0]}), got {jac.shape}")
        a = jac @ qdd
        return a[:3], a[3:]
