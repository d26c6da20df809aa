"""Turning a box held in two palms about the axis through them: how far, and how high.

A two-palm lateral grasp presses on a pair of opposite faces; the line through the palms (the
*grasp axis*) is the one axis the palms can turn the box about without losing their flat
contact: they turn with it about their own normals. Holding the box's y faces, a turn about
the grasp axis is a pitch of the box about its own y axis, and a quarter turn sets the box
down on its side, its x axis vertical.

While it turns, the box's extent below its centre is ``h(theta) = hx |sin theta| + hz |cos
theta|`` (``hx``, ``hz`` its half extents along its x and z axes), whose largest value is
``r = sqrt(hx^2 + hz^2)``, half the diagonal of its x-z face, at ``tan theta = hx / hz``. So a
box turned about the grasp axis clears the table when its centre is at least ``r`` above the
top over the middle of the turn: the lift a turn needs above where the box rests is ``r``
less its resting half height (:func:`turn_lift_m`).

Quaternions are scalar-last ``(x, y, z, w)``; angles rad; lengths m.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

from skills import quaternion as quat
from skills.types import Array

__all__ = [
    "GRASP_AXIS_OBJECT",
    "grasp_axis_turn",
    "sweep_radius_m",
    "turn_lift_m",
    "vertical_half_extent",
]

#: The grasp axis in the object frame: a lateral grasp holds the box's y faces.
GRASP_AXIS_OBJECT = np.array([0.0, 1.0, 0.0])


def vertical_half_extent(extents: ArrayLike, orientation: ArrayLike) -> Array:
    """Half a box's extent along world z when turned by ``orientation``, m.

    Parameters
    ----------
    extents : array_like, shape (3,)
        The box's full extents along its own x, y, z axes, m.
    orientation : array_like, shape (..., 4)
        Unit quaternions, object to world.

    Returns
    -------
    ndarray, shape (...)
        ``0.5 * sum_i |R[2, i]| extents[i]``: how far the box reaches below (and above) its
        centre.
    """
    size = np.asarray(extents, dtype=float)
    up_row = quat.to_matrix(np.asarray(orientation, dtype=float))[..., 2, :]
    return 0.5 * np.abs(up_row) @ size


def grasp_axis_turn(
    start: ArrayLike, goal: ArrayLike, axis_object: ArrayLike = GRASP_AXIS_OBJECT
) -> float:
    """The signed turn (rad) about the object's grasp axis taking ``start`` to ``goal``.

    The rotation from ``start`` to ``goal`` written in the object's own frame (``conj(start)
    goal``), the short way; its rotation vector's component along ``axis_object``. A goal that
    only yaws the object (about world z, with the object upright) turns it by 0 about a
    horizontal grasp axis; a pitch of ``theta`` about the object's y axis turns it by ``theta``.
    """
    rel = quat.multiply(quat.conjugate(np.asarray(start, dtype=float)), np.asarray(goal, float))
    vector = 2.0 * quat.log(quat.canonical(rel))
    axis = np.asarray(axis_object, dtype=float)
    return float(vector @ (axis / np.linalg.norm(axis)))


def sweep_radius_m(extents: ArrayLike) -> float:
    """Half the diagonal of the box's x-z face, m: the most a box turning about its y axis
    reaches below its centre."""
    size = np.asarray(extents, dtype=float)
    return 0.5 * math.hypot(float(size[0]), float(size[2]))


def turn_lift_m(extents: ArrayLike, start: ArrayLike, goal: ArrayLike) -> float:
    """The least lift (m) above the lower of the box's resting heights at ``start`` and
    ``goal`` that keeps its corners off the table while it turns about the grasp axis.

    0 for a move that does not turn the box about its grasp axis (more than a hundredth of a
    radian); else the sweep radius less the lower resting half height.
    """
    if abs(grasp_axis_turn(start, goal)) < 1e-2:
        return 0.0
    rest = min(
        float(vertical_half_extent(extents, start)), float(vertical_half_extent(extents, goal))
    )
    return max(sweep_radius_m(extents) - rest, 0.0)
