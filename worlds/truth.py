"""The physical truth of a run where it differs from what the robot is told.

A world file says what the robot knows: the objects' masses and frictions, the table's
height, where each object stands. :class:`PhysicalTruth` says how the physics differs: the
scene (:class:`worlds.scene.Scene`) builds its bodies from :func:`physical_scene`, scales the
palms' friction and hands the actuators' faults to the controller, while the world spec that
the reasoner, the tree and the skills read stays as the file gives it. Nothing changes during
a run: masses and frictions are set when the scene is built.

The perception error (``sensed_offset_m``, ``sensed_yaw_offset_rad``) is a constant offset on
the object's pose as the robot senses it (:func:`sensed_pose`), from the start until the robot
first holds the object in both palms (:class:`worlds.sim_world.SimWorld`): a camera's error on
an object seen from afar, corrected once the grasp locates it.

A fixture (:class:`FixtureTruth`) may stand elsewhere than the file says, off sideways on the
table top: the robot carries to the slot it was told of and finds the walls by touch.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from skills import quaternion as quat
from worlds.actuators import ActuatorFaults
from worlds.spec import SceneSpec

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class ObjectTruth:
    """How one object differs from its world file entry.

    Attributes
    ----------
    name : str
        The object.
    mass_scale, friction_scale : float
        Its true mass and friction coefficient over the file's, > 0 and >= 0.
    sensed_offset_m : tuple of float
        (2,) error of its sensed position along world x and y, m.
    sensed_yaw_offset_rad : float
        Error of its sensed rotation about world z, rad.
    """

    name: str
    mass_scale: float = 1.0
    friction_scale: float = 1.0
    sensed_offset_m: tuple[float, float] = (0.0, 0.0)
    sensed_yaw_offset_rad: float = 0.0

    def __post_init__(self) -> None:
        numbers = (
            self.mass_scale,
            self.friction_scale,
            *self.sensed_offset_m,
            self.sensed_yaw_offset_rad,
        )
        if (
            len(self.sensed_offset_m) != 2
            or not all(math.isfinite(v) for v in numbers)
            or self.mass_scale <= 0.0
            or self.friction_scale < 0.0
        ):
            raise ValueError(
                f"ObjectTruth {self.name!r}: expected finite numbers, mass_scale > 0, "
                f"friction_scale >= 0 and a (2,) sensed_offset_m, got {self}"
            )

    @property
    def sensed_offset(self) -> bool:
        """Whether the robot senses the object anywhere but where it is."""
        return any(self.sensed_offset_m) or self.sensed_yaw_offset_rad != 0.0

    def summary(self) -> dict[str, Any]:
        """JSON-ready: every value, as held."""
        return {
            "name": self.name,
            "mass_scale": self.mass_scale,
            "friction_scale": self.friction_scale,
            "sensed_offset_m": list(self.sensed_offset_m),
            "sensed_yaw_offset_rad": self.sensed_yaw_offset_rad,
        }


@dataclass(frozen=True)
class FixtureTruth:
    """How one fixture's place differs from its world file entry.

    Attributes
    ----------
    name : str
        The fixture.
    offset_m : tuple of float
        (2,) its true centre less the file's, along world x and y, m.
    """

    name: str
    offset_m: tuple[float, float] = (0.0, 0.0)

    def __post_init__(self) -> None:
        if len(self.offset_m) != 2 or not all(math.isfinite(v) for v in self.offset_m):
            raise ValueError(
                f"FixtureTruth {self.name!r}: expected a finite (2,) offset_m, got {self.offset_m}"
            )

    def summary(self) -> dict[str, Any]:
        """JSON-ready: every value, as held."""
        return {"name": self.name, "offset_m": list(self.offset_m)}


@dataclass(frozen=True)
class PhysicalTruth:
    """How a run's physics differs from its world file; the default differs in nothing.

    Attributes
    ----------
    objects : tuple of ObjectTruth
        Per object; an object not named here is as its file entry says.
    palm_friction_scale : float
        Both palms' true friction coefficient over their model's, >= 0.
    table_dz_m : float
        The table top's true height less the file's, m; every object starts resting on it.
    actuators : ActuatorFaults or None
        The arms' actuators (:mod:`worlds.actuators`); None: ideal.
    fixtures : tuple of FixtureTruth
        Per fixture; a fixture not named here stands where its file entry says (on the
        table top, raised with it by ``table_dz_m``).
    """

    objects: tuple[ObjectTruth, ...] = ()
    palm_friction_scale: float = 1.0
    table_dz_m: float = 0.0
    actuators: ActuatorFaults | None = None
    fixtures: tuple[FixtureTruth, ...] = ()

    def __post_init__(self) -> None:
        if not (math.isfinite(self.palm_friction_scale) and self.palm_friction_scale >= 0.0):
            raise ValueError(
                f"PhysicalTruth: expected palm_friction_scale finite and >= 0, "
                f"got {self.palm_friction_scale}"
            )
        if not math.isfinite(self.table_dz_m):
            raise ValueError(f"PhysicalTruth: expected table_dz_m finite, got {self.table_dz_m}")
        for kind, items in (("object", self.objects), ("fixture", self.fixtures)):
            names = [o.name for o in items]
            if len(set(names)) != len(names):
                raise ValueError(f"PhysicalTruth: expected each {kind} once, got {names}")

    def of(self, name: str) -> ObjectTruth:
        """The truth of object ``name`` (as its file entry says if not named here)."""
        return next((o for o in self.objects if o.name == name), ObjectTruth(name))

    def fixture_shift(self, name: str) -> FloatArray:
        """Where fixture ``name`` truly stands less where the file says, (3,) m, world frame:
        its own sideways offset and the table's height."""
        t = next((f for f in self.fixtures if f.name == name), FixtureTruth(name))
        return np.array([*t.offset_m, self.table_dz_m], dtype=float)

    def summary(self) -> dict[str, Any]:
        """JSON-ready: every value, as held."""
        return {
            "objects": [o.summary() for o in self.objects],
            "palm_friction_scale": self.palm_friction_scale,
            "table_dz_m": self.table_dz_m,
            "actuators": None if self.actuators is None else self.actuators.summary(),
            "fixtures": [f.summary() for f in self.fixtures],
        }


def true_goal_position(
    position: ArrayLike,
    orientation: ArrayLike,
    extents: ArrayLike,
    table_top_z: float,
    table_dz_m: float,
) -> FloatArray:
    """Where a goal is in the physics: one that rests the object on the table's top as the
    file states it (its lowest point within 1 mm of ``table_top_z``) is raised with the true
    top by ``table_dz_m``; any other goal is where it is.

    Parameters
    ----------
    position, orientation : array_like
        The goal's centre (3,), m, and orientation (4,), scalar-last, world frame.
    extents : array_like
        (3,) the object's box extents, m.
    table_top_z : float
        The file's table top height, m.
    table_dz_m : float
        :attr:`PhysicalTruth.table_dz_m`.
    """
    p = np.array(position, dtype=float)
    # The object's half height in world z, turned as the goal turns it.
    half_z = 0.5 * float(np.abs(quat.to_matrix(np.asarray(orientation, float))[2]) @ extents)
    if abs(p[2] - half_z - table_top_z) <= 1e-3:
        p[2] += table_dz_m
    return p


def physical_scene(spec: SceneSpec, truth: PhysicalTruth) -> SceneSpec:
    """The scene as the physics builds it: true masses and frictions, the table's top
    ``table_dz_m`` higher (its height above the floor with it), each object and fixture that
    much higher, each fixture moved by its offset.

    Raises
    ------
    ValueError
        If the truth names an object or a fixture the scene lacks, or the table would sink
        into the floor.
    """
    for kind, have, named in (
        ("object", spec.objects, truth.objects),
        ("fixture", spec.fixtures, truth.fixtures),
    ):
        names = [o.name for o in have]
        unknown = [o.name for o in named if o.name not in names]
        if unknown:
            raise ValueError(f"physical_scene: expected {kind} names in {names}, got {unknown}")
    dz = truth.table_dz_m
    table = spec.table
    if table.size[2] + dz <= 0.0:
        raise ValueError(
            f"physical_scene: expected table_dz_m > -{table.size[2]} m (the table's height), "
            f"got {dz}"
        )
    x, y, z = table.position
    sx, sy, sz = table.size
    objects = []
    for obj in spec.objects:
        t = truth.of(obj.name)
        px, py, pz = obj.position
        objects.append(
            replace(
                obj,
                mass=obj.mass * t.mass_scale,
                friction=obj.friction * t.friction_scale,
                position=(px, py, pz + dz),
            )
        )
    fixtures = []
    for fixture in spec.fixtures:
        fx, fy, fz = (
            float(v) for v in np.asarray(fixture.position) + truth.fixture_shift(fixture.name)
        )
        fixtures.append(replace(fixture, position=(fx, fy, fz)))
    return replace(
        spec,
        table=replace(table, position=(x, y, z + dz), size=(sx, sy, sz + dz)),
        objects=tuple(objects),
        fixtures=tuple(fixtures),
    )


def sensed_pose(
    position: ArrayLike, quaternion: ArrayLike, truth: ObjectTruth
) -> tuple[FloatArray, FloatArray]:
    """An object's pose as the robot senses it: moved by ``sensed_offset_m`` along world x
    and y and turned by ``sensed_yaw_offset_rad`` about world z.

    Parameters
    ----------
    position : array_like
        (3,) true centre, world frame, m.
    quaternion : array_like
        (4,) true orientation, scalar-last.
    truth : ObjectTruth

    Returns
    -------
    ndarray, ndarray
        (3,) sensed centre, m, and (4,) sensed orientation, scalar-last.
    """
    dx, dy = truth.sensed_offset_m
    sensed = np.asarray(position, dtype=float) + np.array([dx, dy, 0.0])
    turn = quat.from_axis_angle(np.array([0.0, 0.0, 1.0]), truth.sensed_yaw_offset_rad)
    return sensed, np.asarray(quat.multiply(turn, np.asarray(quaternion, dtype=float)))


__all__ = [
    "FixtureTruth",
    "ObjectTruth",
    "PhysicalTruth",
    "physical_scene",
    "sensed_pose",
    "true_goal_position",
]
