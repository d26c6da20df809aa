"""Dual-arm modelling in two orthogonal spaces (the paper's Sec. 2.3 and eq. 5).

- The absolute space is the held object's pose ``object2world`` (frame {O}, the centre of the
  closed chain).
- The relative space is each palm's pose in {O}, ``palm2object``; the grasp geometry gives the
  contact poses there.
- The grasp map ``G = [G_L G_R]`` (6 x 12), ``G_i = [[I, 0], [S(r_i), I]]`` with ``r_i`` the
  world-frame vector from the object centre to contact ``i``, so that ``G^T [v; w]`` gives each
  contact the rigid-body twist ``[v + w x r_i; w]``.
- Composition (eq. 5): ``[y_L'; y_R'] = G^T sum_j w_j y_o_j' + sum_k w_k [y_CL_k'; y_CR_k']``
  with every ``y'`` a 6-D twist (linear, angular) and the relative twists rotated from {O}
  into the world frame.

Twists are ``(6,)`` arrays ``[vx, vy, vz, wx, wy, wz]``: the velocity of the named point and
the angular velocity, both in the world frame unless a name says otherwise.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from skills import quaternion as quat
from skills.types import Array
from skills.vocabulary import Arm

__all__ = [
    "GraspGeometry",
    "contact_twists",
    "grasp_matrix",
    "integrate_twist",
    "shift_along_face",
    "skew",
]


def skew(r: ArrayLike) -> Array:
    """Cross-product matrices ``S(r)`` with ``S(r) @ x = r x x``; ``(..., 3) -> (..., 3, 3)``."""
    v = np.asarray(r, dtype=float)
    s = np.zeros((*v.shape[:-1], 3, 3))
    s[..., 0, 1], s[..., 0, 2] = -v[..., 2], v[..., 1]
    s[..., 1, 0], s[..., 1, 2] = v[..., 2], -v[..., 0]
    s[..., 2, 0], s[..., 2, 1] = -v[..., 1], v[..., 0]
    return s


def grasp_matrix(contacts_from_centre: ArrayLike) -> Array:
    """The grasp map ``G`` (6 x 6n) for contacts at ``r_i`` from the object centre.

    Parameters
    ----------
    contacts_from_centre : array_like, shape (n, 3)
        World-frame vectors from the object centre to each contact, m.

    Returns
    -------
    ndarray, shape (6, 6 n)
        ``G = [G_1 ... G_n]``, ``G_i = [[I, 0], [S(r_i), I]]``: ``G @ wrenches`` sums contact
        wrenches at the centre, ``G.T @ twist`` gives each contact's rigid-body twist.
    """
    r = np.asarray(contacts_from_centre, dtype=float)
    if r.ndim != 2 or r.shape[1] != 3:
        raise ValueError(f"contacts_from_centre: expected shape (n, 3), got {r.shape}")
    n = r.shape[0]
    g = np.zeros((6, 6 * n))
    eye = np.eye(3)
    for i in range(n):  # n is the number of contacts (2), not samples
        g[:3, 6 * i : 6 * i + 3] = eye
        g[3:, 6 * i : 6 * i + 3] = skew(r[i])
        g[3:, 6 * i + 3 : 6 * i + 6] = eye
    return g


def contact_twists(object_twist: ArrayLike, contacts_from_centre: ArrayLike) -> Array:
    """``G^T`` applied without building ``G``: each contact's twist ``[v + w x r_i; w]``.

    Parameters
    ----------
    object_twist : array_like, shape (..., 6)
        Object centre's linear and angular velocity, world frame.
    contacts_from_centre : array_like, shape (n, 3)

    Returns
    -------
    ndarray, shape (..., n, 6)
    """
    t = np.asarray(object_twist, dtype=float)
    r = np.asarray(contacts_from_centre, dtype=float)
    v = t[..., None, :3]
    w = t[..., None, 3:]
    out = np.empty((*t.shape[:-1], r.shape[0], 6))
    out[..., :3] = v + np.cross(w, r)
    out[..., 3:] = w
    return out


@dataclass(frozen=True)
class GraspGeometry:
    """Contact poses of the palms in the object frame {O}: the relative-space reference.

    Attributes
    ----------
    left_position, right_position : ndarray, shape (3,)
        Palm centre in {O} (``palm2object`` translation), m.
    left_orientation, right_orientation : ndarray, shape (4,)
        Palm orientation in {O} (``palm2object`` rotation), quaternion ``(x, y, z, w)``.
    left_normal, right_normal : ndarray, shape (3,)
        Inward contact normal in {O}: the direction the palm pushes the object.
    """

    left_position: Array
    left_orientation: Array
    right_position: Array
    right_orientation: Array
    left_normal: Array
    right_normal: Array

    @staticmethod
    def lateral(
        width: float,
        palm_thickness: float = 0.0,
        normal_axis: ArrayLike = (0.0, 0.0, 1.0),
        down_axis: ArrayLike = (1.0, 0.0, 0.0),
        quarter_turns: int = 0,
        height: float = 0.0,
    ) -> GraspGeometry:
        """Two palms flat on the object's +y (left) and -y (right) faces, or on the pair of
        side faces ``quarter_turns`` quarter turns about the object's z axis from them.

        Parameters
        ----------
        width : float
            Distance between the two faces along the object's y axis, m (> 0).
        palm_thickness : float
            Palm thickness along its normal, m: the palm frame sits at the palm's centre, half
            of it outside the face.
        normal_axis : array_like, shape (3,)
            The palm-frame axis that points out of the contact face, into the object.
        down_axis : array_like, shape (3,)
            The palm-frame axis that should point down (along the object's -z).
        quarter_turns : int
            Which pair of side faces: 0 the +-y faces (left on +y), 1 the left palm on the
            -x face, 2 on -y, 3 on +x (:mod:`skills.turns`). ``width`` is the distance
            between the faces of that pair.
        height : float
            Palm centres above the object's centre along its z axis, m (0: centred on the
            faces; :func:`skills.insertion.grasp_height` raises them over a fixture's walls).
        """
        if not (np.isfinite(width) and width > 0):
            raise ValueError(f"width: expected a positive distance in m, got {width!r}")
        if not (np.isfinite(palm_thickness) and palm_thickness >= 0):
            raise ValueError(
                f"palm_thickness: expected a distance >= 0 in m, got {palm_thickness!r}"
            )
        n = np.asarray(normal_axis, dtype=float)
        d = np.asarray(down_axis, dtype=float)
        if abs(float(np.dot(n, d))) > 1e-9 * np.linalg.norm(n) * np.linalg.norm(d):
            raise ValueError("down_axis: expected an axis perpendicular to normal_axis")
        offset = width / 2.0 + palm_thickness / 2.0
        left_in = np.array([0.0, -1.0, 0.0])  # the left palm pushes towards -y
        right_in = np.array([0.0, 1.0, 0.0])
        turn = quat.from_axis_angle(np.array([0.0, 0.0, 1.0]), int(quarter_turns) * np.pi / 2.0)
        up = np.array([0.0, 0.0, float(height)])
        return GraspGeometry(
            quat.rotate(turn, np.array([0.0, offset, 0.0])) + up,
            quat.multiply(turn, _frame(n, d, left_in)),
            quat.rotate(turn, np.array([0.0, -offset, 0.0])) + up,
            quat.multiply(turn, _frame(n, d, right_in)),
            quat.rotate(turn, left_in),
            quat.rotate(turn, right_in),
        )

    def position(self, arm: Arm) -> Array:
        """Palm centre in {O}, (3,)."""
        return self.left_position if arm is Arm.LEFT else self.right_position

    def orientation(self, arm: Arm) -> Array:
        """Palm orientation in {O}, (4,)."""
        return self.left_orientation if arm is Arm.LEFT else self.right_orientation

    def normal(self, arm: Arm) -> Array:
        """Inward contact normal in {O}, (3,)."""
        return self.left_normal if arm is Arm.LEFT else self.right_normal

    def squeezed(self, depth: float) -> GraspGeometry:
        """The same contacts moved ``depth`` m inwards along their normals (a squeeze offset)."""
        return GraspGeometry(
            self.left_position + depth * self.left_normal,
            self.left_orientation,
            self.right_position + depth * self.right_normal,
            self.right_orientation,
            self.left_normal,
            self.right_normal,
        )


def _frame(normal_axis: Array, down_axis: Array, inward: Array) -> Array:
    """Rotation (4,) taking ``normal_axis`` onto ``inward`` and ``down_axis`` onto -z."""
    n = normal_axis / np.linalg.norm(normal_axis)
    d = down_axis / np.linalg.norm(down_axis)
    down = np.array([0.0, 0.0, -1.0])
    body = np.stack((n, d, np.cross(n, d)), axis=1)
    world = np.stack((inward, down, np.cross(inward, down)), axis=1)
    return quat.from_matrix(world @ body.T)


def integrate_twist(
    position: Array, orientation: Array, twist: Array, dt: float
) -> tuple[Array, Array]:
    """Move a frame by a constant world-frame twist for ``dt``: the exact screw motion.

    The twist is ``[v_p; w]``, the velocity of the frame's origin ``p`` and the angular
    velocity. Every point of a rigid body moved this way by its own ``[v + w x r; w]`` lands
    where the body's single rigid motion puts it, so frames integrated separately with twists
    from the grasp map stay rigidly attached to rounding error.

    Parameters
    ----------
    position : ndarray, shape (..., 3)
    orientation : ndarray, shape (..., 4)
    twist : ndarray, shape (..., 6)
    dt : float

    Returns
    -------
    position, orientation : ndarray, shapes (..., 3), (..., 4)
    """
    v = twist[..., :3]
    phi = twist[..., 3:] * dt
    theta = np.linalg.norm(phi, axis=-1, keepdims=True)
    small = theta < 1e-8
    th = np.where(small, 1.0, theta)
    # Left Jacobian of SO(3): displacement = dt * J(phi) v
    a = np.where(small, 0.5 - theta**2 / 24.0, (1.0 - np.cos(th)) / th**2)
    b = np.where(small, 1.0 / 6.0 - theta**2 / 120.0, (th - np.sin(th)) / th**3)
    pv = np.cross(phi, v)
    disp = v + a * pv + b * np.cross(phi, pv)
    new_orientation = quat.multiply(quat.exp(0.5 * phi), orientation)
    return position + disp * dt, new_orientation


def shift_along_face(palm2object: ArrayLike, reference: ArrayLike) -> Array:
    """How far palms have moved along the faces they hold since ``reference``, m.

    The displacement of each palm in {O} less its component along the reference's line from
    the object's centre (for a face held at its middle, the face normal): a squeeze settling in
    or a palm pressing deeper is not a slip; a palm sliding along the face, or the object
    turning or dropping in the grip, is.

    Parameters
    ----------
    palm2object : array_like
        (..., 3) palm positions in {O} now, m.
    reference : array_like
        (..., 3) their positions in {O} when the grasp was made, m (not at the centre).

    Returns
    -------
    ndarray
        (...) distances, m.
    """
    now = np.asarray(palm2object, dtype=float)
    ref = np.asarray(reference, dtype=float)
    normal = ref / np.linalg.norm(ref, axis=-1, keepdims=True)
    moved = now - ref
    along = moved - np.sum(moved * normal, axis=-1, keepdims=True) * normal
    return np.asarray(np.linalg.norm(along, axis=-1))
