"""An object's extents as the affordance stages read them, and the pairs of parallel faces a
lateral squeeze can press on.

Which shapes offer two parallel faces for a squeeze:

- box: the two pairs of side faces (x and y of {O}); the top and bottom are not reachable
  from the sides;
- cylinder (axis along z of {O}): two palms on planes tangent to opposite sides of the
  diameter are parallel, and each touches the cylinder along a vertical line as tall as the
  cylinder, which resists tipping about the line joining the contacts; so it counts, with
  the diameter as the span;
- sphere: no; each palm touches a single point, and two point contacts cannot stop the
  sphere spinning about the line joining them;
- mesh: the pairs of sides of its convex hull the world found pressable across x and y of
  {O} (``ObjectContext.squeeze_axes``, :mod:`worlds.mesh_sides`), as a box's of its bounding
  box; none, or only point contacts, and no.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import StrEnum

from affordances.context import ObjectContext, Shape, Vector3


class FaceAxis(StrEnum):
    """Normal of a pair of parallel faces in {O}; ``diameter`` is any horizontal one."""

    X = "x"
    Y = "y"
    DIAMETER = "diameter"


@dataclass(frozen=True)
class FacePair:
    """Two parallel faces a lateral squeeze can press on.

    Attributes
    ----------
    axis : FaceAxis
        Normal of the faces in {O}.
    separation_m : float
        Distance between the faces, metres: the palm span the squeeze needs.
    contact_height_m : float
        Height of the faces, metres.
    """

    axis: FaceAxis
    separation_m: float
    contact_height_m: float


def horizontal_extents(context: ObjectContext) -> tuple[float, float]:
    """Full extents along x and y of {O}, metres."""
    dims = context.dimensions
    if context.shape in (Shape.BOX, Shape.MESH):
        return dims[0], dims[1]
    return 2.0 * dims[0], 2.0 * dims[0]


def object_height(context: ObjectContext) -> float:
    """Full extent along z of {O}, metres."""
    dims = context.dimensions
    if context.shape in (Shape.BOX, Shape.MESH):
        return dims[2]
    if context.shape == Shape.CYLINDER:
        return dims[1]
    return 2.0 * dims[0]


def grip_width(context: ObjectContext) -> float:
    """Narrowest horizontal extent, metres: what one hand must close around."""
    return min(horizontal_extents(context))


def bounding_radius(context: ObjectContext) -> float:
    """Radius of the sphere about the object's centre that contains it, metres."""
    dims = context.dimensions
    if context.shape in (Shape.BOX, Shape.MESH):
        return 0.5 * math.hypot(*dims)
    if context.shape == Shape.CYLINDER:
        return math.hypot(dims[0], 0.5 * dims[1])
    return dims[0]


def parallel_face_pairs(context: ObjectContext) -> tuple[FacePair, ...]:
    """Pairs of parallel faces a lateral squeeze could press on (see the module docstring)."""
    height = object_height(context)
    if context.shape == Shape.BOX:
        ex, ey = horizontal_extents(context)
        return (FacePair(FaceAxis.X, ex, height), FacePair(FaceAxis.Y, ey, height))
    if context.shape == Shape.MESH:
        ex, ey = horizontal_extents(context)
        pairs = (FacePair(FaceAxis.X, ex, height), FacePair(FaceAxis.Y, ey, height))
        return tuple(p for p in pairs if p.axis.value in context.squeeze_axes)
    if context.shape == Shape.CYLINDER:
        return (FacePair(FaceAxis.DIAMETER, 2.0 * context.dimensions[0], height),)
    return ()


def axis_in_world(axis: FaceAxis, yaw: float) -> Vector3:
    """Unit vector of a face normal in {W}; a cylinder's diameter is taken along world y."""
    if axis == FaceAxis.X:
        return (math.cos(yaw), math.sin(yaw), 0.0)
    if axis == FaceAxis.Y:
        return (-math.sin(yaw), math.cos(yaw), 0.0)
    return (0.0, 1.0, 0.0)


__all__ = [
    "FaceAxis",
    "FacePair",
    "axis_in_world",
    "bounding_radius",
    "grip_width",
    "horizontal_extents",
    "object_height",
    "parallel_face_pairs",
]
