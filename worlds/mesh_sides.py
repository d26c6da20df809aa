"""Where a mesh object can be squeezed: the sides of its convex hull a flat palm presses on.

The physics holds a mesh object by its convex hull, so a palm pressing along a body axis
touches the hull's extreme there: the vertices within :data:`SIDE_TOLERANCE_M` of its
farthest plane. A lateral squeeze along the object's x or y axis (as a box's, through its
centre, at its middle height) holds when, on both sides, that contact

- reaches up and down the object, over at least :data:`MIN_CONTACT_HEIGHT` of its height (a
  flat face, or a vertical edge as a cylinder's line of contact); a pointed or tapered side
  touches at one corner and the object tips about it;
- lies across the squeeze line: it spans the object's centre across the axis, within
  :data:`SIDE_TOLERANCE_M` (a vertical edge on the line, as a prism's).

A mesh object's positions are its body origin's, and its grasps, rests and clearances are
reckoned from the centre of its bounding box: :func:`mesh_centre` says where that is, and a
world whose object mesh is off its origin is refused (:mod:`worlds.feasibility`).
"""

from __future__ import annotations

import numpy as np

from worlds.spec import ShapeSpec

#: How close to a side's farthest plane a hull vertex touches the palm, m.
SIDE_TOLERANCE_M = 0.002

#: Least share of the object's height a side's contact must reach over.
MIN_CONTACT_HEIGHT = 0.5

#: How far a mesh's bounding-box centre may be from its origin, m.
CENTRE_TOLERANCE_M = 0.001


def mesh_centre(shape: ShapeSpec) -> np.ndarray:
    """Centre (3,) of the bounding box of a mesh shape's scaled vertices, body frame, m."""
    vertices = shape.mesh_vertices()
    return 0.5 * (vertices.max(axis=0) + vertices.min(axis=0))


def _side_holds(vertices: np.ndarray, axis: int, sign: float) -> bool:
    """Whether the hull's extreme along ``sign`` times body ``axis`` is a contact a squeeze
    holds on (see the module)."""
    across = 1 - axis  # the other horizontal axis
    along = sign * vertices[:, axis]
    touching = vertices[along >= along.max() - SIDE_TOLERANCE_M]
    low, high = vertices[:, 2].min(), vertices[:, 2].max()
    tall = np.ptp(touching[:, 2]) >= MIN_CONTACT_HEIGHT * (high - low)
    centre = 0.5 * (vertices[:, across].min() + vertices[:, across].max())
    spans = (
        touching[:, across].min() - SIDE_TOLERANCE_M
        <= centre
        <= touching[:, across].max() + SIDE_TOLERANCE_M
    )
    return bool(tall and spans)


def squeeze_axes(shape: ShapeSpec) -> tuple[str, ...]:
    """The body axes, of ``"x"`` and ``"y"``, along which both sides of a mesh shape's hull
    hold a lateral squeeze (see the module)."""
    vertices = shape.mesh_vertices()
    return tuple(
        name
        for axis, name in ((0, "x"), (1, "y"))
        if _side_holds(vertices, axis, 1.0) and _side_holds(vertices, axis, -1.0)
    )


__all__ = [
    "CENTRE_TOLERANCE_M",
    "MIN_CONTACT_HEIGHT",
    "SIDE_TOLERANCE_M",
    "mesh_centre",
    "squeeze_axes",
]
