"""Fit the insertion's force coupling (:func:`skills.insertion.admittance_step`) to a teacher.

The demonstration (``demos/insertion.csv``) holds the box's pose, the teacher's plan
(``bx, by, bz``) and the force the fixture exerted on the box (``fx, fy, fz``). Sideways the
teacher follows the plan with a lag and yields to the wall: ``v = c f + k (plan - p)``, one
compliance ``c`` and one centring ``k`` shared by x and y, fitted by linear least squares.
The slow-down bounds are not identifiable from a few contacts; they are set
(:data:`SOFT_FORCE_N`, :data:`STOP_FORCE_N`) from the judge's limit, as written there.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from skills.demos.io import DemoFile, columns
from skills.insertion import AdmittanceGains

#: The descent stops at 15 N: the judge allows no wall more than 20 N for over 0.5 s, and a
#: stopped descent with the targets still shifting away lets the force fall well within that;
#: 5 N of margin covers one control period's rise at the descent's speed against a wall
#: (0.05 m/s x 1/60 s into a 4000 N/m contact is 3.3 N). It slows from a third of that.
STOP_FORCE_N = 15.0
SOFT_FORCE_N = 5.0


@dataclass(frozen=True)
class InsertionFit:
    """The fitted coupling and how well it explains the teacher.

    Attributes
    ----------
    gains : AdmittanceGains
    residual_rms : float
        RMS of the sideways velocity the fit leaves unexplained, m/s.
    relative_residual : float
        ``residual_rms`` over the RMS of the sideways velocity.
    contact_samples : int
        Samples with the fixture pressing the box.
    """

    gains: AdmittanceGains
    residual_rms: float
    relative_residual: float
    contact_samples: int


def fit_insertion(demo_file: DemoFile) -> InsertionFit:
    """Least-squares compliance and centring from an insertion demonstration.

    Raises
    ------
    ValueError
        If the teacher never touched the fixture, or the fit is not a compliance (c <= 0).
    """
    demo = demo_file.demonstration
    force = columns(demo_file, ["fx", "fy", "fz"])
    plan = columns(demo_file, ["bx", "by", "bz"])
    v, _ = demo.position_derivatives()
    beyond = v[:, :2].reshape(-1)
    rows = np.stack([force[:, :2].reshape(-1), (plan - demo.positions)[:, :2].reshape(-1)], axis=1)
    touching = int(np.count_nonzero(np.linalg.norm(force, axis=1) > 0))
    if touching == 0:
        raise ValueError(f"{demo.name}: fx, fy, fz: expected the box to touch the fixture")
    sol, *_ = np.linalg.lstsq(rows, beyond, rcond=None)
    c, k = float(sol[0]), float(sol[1])
    if not c > 0:
        raise ValueError(f"{demo.name}: expected a compliant teacher (c > 0), got c={c:.3g}")
    residual = rows @ sol - beyond
    rms = float(np.sqrt(np.mean(residual**2)))
    scale = max(float(np.sqrt(np.mean(beyond**2))), 1e-12)
    return InsertionFit(
        AdmittanceGains(c, max(k, 0.0), SOFT_FORCE_N, STOP_FORCE_N), rms, rms / scale, touching
    )


__all__ = ["SOFT_FORCE_N", "STOP_FORCE_N", "InsertionFit", "fit_insertion"]
