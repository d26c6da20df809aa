"""Canonical system (phase) and the normalised Gaussian RBF basis of the forcing term.

The phase obeys ``tau * sdot = -alpha_s * s`` with ``s(0) = 1`` (Ijspeert et al. 2013), so
``s(t) = exp(-alpha_s * t / tau)``. Basis centres are spread evenly in time, i.e.
exponentially in phase, and each width is set from the distance to the next centre.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np
from numpy.typing import ArrayLike

from skills.types import Array

#: Phase decay: ``s(tau) = exp(-4.605) = 0.01``.
DEFAULT_ALPHA_S = -math.log(0.01)


def phase(t: ArrayLike, tau: float, alpha_s: float = DEFAULT_ALPHA_S) -> Array:
    """Phase ``s(t) = exp(-alpha_s t / tau)`` for times ``t`` (s) since the start."""
    return np.exp(-alpha_s * np.asarray(t, dtype=float) / tau)


def phase_step(s: float, dt: float, tau: float, alpha_s: float = DEFAULT_ALPHA_S) -> float:
    """Advance the phase by ``dt`` seconds (exact solution of the linear canonical system)."""
    return s * math.exp(-alpha_s * dt / tau)


@dataclass(frozen=True, eq=False)
class RBFBasis:
    """Gaussian basis ``psi_i(s) = exp(-h_i (s - c_i)^2)`` over the phase.

    Attributes
    ----------
    centres : ndarray, shape (K,)
        Centres in phase, from 1 (start) down to ``exp(-alpha_s)`` (end).
    widths : ndarray, shape (K,)
        Inverse squared widths ``h_i``.
    """

    centres: Array
    widths: Array

    @cached_property
    def exponent_table(self) -> Array:
        """``T`` with ``[s^2, s, 1] @ T = -h (s - c)^2``, shape (3, K).

        Expanding the square turns one phase's exponents into a single small product, which
        is what a per-step evaluation wants.
        """
        h, c = self.widths, self.centres
        return np.stack((-h, 2.0 * h * c, -h * c * c))

    def activations_at(self, s: float) -> Array:
        """Unnormalised ``psi(s)``, shape (K,), for one phase value (the per-step path).

        The last phase's activations are kept: in one composition step the shared basis is
        read at the same phase by every learnt skill. Treat the result as read-only.
        """
        cache = self.__dict__.get("_last")
        if cache is not None and cache[0] == s:
            return cache[1]
        psi = np.exp(np.array((s * s, s, 1.0)) @ self.exponent_table)
        self.__dict__["_last"] = (s, psi)
        return psi

    def same_as(self, other: RBFBasis) -> bool:
        """Whether ``other`` has the same centres and widths (the same functions)."""
        if self is other:
            return True
        return np.array_equal(self.centres, other.centres) and np.array_equal(
            self.widths, other.widths
        )

    @property
    def size(self) -> int:
        """Number of basis functions ``K``."""
        return int(self.centres.shape[0])

    def normalised(self, s: ArrayLike) -> Array:
        """Normalised activations ``psi_i(s) / sum_j psi_j(s)``, shape ``(..., K)``."""
        s_arr = np.asarray(s, dtype=float)[..., None]
        psi = np.exp(-self.widths * (s_arr - self.centres) ** 2)
        total = psi.sum(axis=-1, keepdims=True)
        return psi / np.maximum(total, 1e-300)


def make_basis(n_basis: int, alpha_s: float = DEFAULT_ALPHA_S, overlap: float = 0.5) -> RBFBasis:
    """Basis of ``n_basis`` Gaussians spread evenly in time over one ``tau``.

    Parameters
    ----------
    n_basis : int
        Number of basis functions, at least 1.
    alpha_s : float
        Phase decay constant.
    overlap : float
        Activation of a Gaussian at its neighbour's centre, in (0, 1); larger is wider.

    Returns
    -------
    RBFBasis
    """
    if not isinstance(n_basis, int | np.integer) or n_basis < 1:
        raise ValueError(f"n_basis: expected an integer >= 1, got {n_basis!r}")
    if not 0.0 < overlap < 1.0:
        raise ValueError(f"overlap: expected a value in (0, 1), got {overlap!r}")
    if not alpha_s > 0.0:
        raise ValueError(f"alpha_s: expected a positive number, got {alpha_s!r}")
    centres = np.exp(-alpha_s * np.linspace(0.0, 1.0, n_basis))
    if n_basis == 1:
        return RBFBasis(centres=centres, widths=np.array([1.0]))
    gaps = np.abs(np.diff(centres))
    gaps = np.append(gaps, gaps[-1])
    # exp(-h * gap^2) = overlap  =>  h = -ln(overlap) / gap^2
    widths = -math.log(overlap) / gaps**2
    return RBFBasis(centres=centres, widths=widths)
