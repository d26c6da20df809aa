"""What the reasoner knows about an object, its surroundings and the robot.

Positions are in the world frame {W} (+z up), in metres; the robot's own frame in it (+x
forward, +y to its left) is :attr:`RobotCapabilities.base_pose`, the origin's unless the robot
stands elsewhere or turned. Yaw is the object's rotation about world z, in radians.
Vectors are stored as tuples of floats so the values stay frozen, hashable and comparable.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from enum import Enum, StrEnum
from typing import Any, TypeVar

from skills.vocabulary import EndEffector

Vector3 = tuple[float, float, float]

_E = TypeVar("_E", bound=Enum)


class Shape(StrEnum):
    """Shape primitive of an object; fixes how ``dimensions`` is read."""

    BOX = "box"
    CYLINDER = "cylinder"
    SPHERE = "sphere"
    MESH = "mesh"


class Fragility(StrEnum):
    """How much squeezing and shock an object tolerates."""

    ROBUST = "robust"
    NORMAL = "normal"
    FRAGILE = "fragile"


class ObjectState(StrEnum):
    """Discrete state facts about an object (containers, trays, hot items)."""

    OPEN = "open"
    CLOSED = "closed"
    FULL = "full"
    EMPTY = "empty"
    HOT = "hot"
    CONTAINS_ITEMS = "contains_items"


#: What ``dimensions`` holds for each shape, in metres. Meshes give their bounding-box extents.
DIMENSION_NAMES: Mapping[Shape, tuple[str, ...]] = {
    Shape.BOX: ("x", "y", "z"),
    Shape.CYLINDER: ("radius", "height"),
    Shape.SPHERE: ("radius",),
    Shape.MESH: ("x", "y", "z"),
}

_CONTRADICTIONS = (
    (ObjectState.OPEN, ObjectState.CLOSED),
    (ObjectState.FULL, ObjectState.EMPTY),
)


def _where(owner: str, field_name: str) -> str:
    return f"{owner}.{field_name}" if owner else field_name


def check_finite(value: Any, owner: str, field_name: str) -> float:
    """Coerce ``value`` to a finite float or raise ``ValueError`` naming the field.

    Parameters
    ----------
    value : Any
        Number to check.
    owner : str
        Name of the value that holds the field, used in the message.
    field_name : str
        Name of the field, used in the message.

    Returns
    -------
    float
        The value as a float.
    """
    where = _where(owner, field_name)
    if isinstance(value, bool):
        raise ValueError(f"{where}: expected a number, got bool {value!r}")
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{where}: expected a number, got {value!r}") from None
    if not math.isfinite(number):
        raise ValueError(f"{where}: expected a finite number, got {number!r}")
    return number


def check_positive(value: Any, owner: str, field_name: str, unit: str = "") -> float:
    """Coerce ``value`` to a finite float > 0 or raise ``ValueError`` naming the field."""
    number = check_finite(value, owner, field_name)
    if number <= 0.0:
        raise ValueError(f"{_where(owner, field_name)}: expected > 0{unit}, got {number!r}")
    return number


def check_non_negative(value: Any, owner: str, field_name: str) -> float:
    """Coerce ``value`` to a finite float >= 0 or raise ``ValueError`` naming the field."""
    number = check_finite(value, owner, field_name)
    if number < 0.0:
        raise ValueError(f"{_where(owner, field_name)}: expected >= 0, got {number!r}")
    return number


def check_vector3(value: Any, owner: str, field_name: str) -> Vector3:
    """Coerce ``value`` to a tuple of three finite floats or raise ``ValueError``."""
    where = _where(owner, field_name)
    if isinstance(value, str | bytes) or not isinstance(value, Iterable):
        raise ValueError(f"{where}: expected 3 numbers (x, y, z), got {value!r}")
    items = list(value)
    if len(items) != 3:
        raise ValueError(f"{where}: expected 3 numbers (x, y, z), got {len(items)}: {items!r}")
    x, y, z = (check_finite(v, owner, f"{field_name}[{i}]") for i, v in enumerate(items))
    return (x, y, z)


def check_enum(value: Any, enum_cls: type[_E], owner: str, field_name: str) -> _E:
    """Coerce ``value`` (a member or its value) to ``enum_cls`` or raise ``ValueError``."""
    if isinstance(value, enum_cls):
        return value
    try:
        return enum_cls(value)
    except ValueError:
        allowed = ", ".join(str(m.value) for m in enum_cls)
        raise ValueError(
            f"{_where(owner, field_name)}: expected one of {allowed}, got {value!r}"
        ) from None


def check_text(value: Any, owner: str, field_name: str) -> str:
    """Return ``value`` stripped and lower-cased, or raise if it is not a non-empty string."""
    if not isinstance(value, str) or not value.strip():
        raise ValueError(f"{_where(owner, field_name)}: expected a non-empty string, got {value!r}")
    return value.strip().lower()


@dataclass(frozen=True)
class Obstacle:
    """Something near the object that the object and the arms must not touch.

    Attributes
    ----------
    name : str
        Name of the obstacle in the world.
    position : tuple of float, shape (3,)
        Centre in {W}, metres.
    radius : float
        Radius of a bounding sphere, metres (> 0).
    """

    name: str
    position: Vector3
    radius: float

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name:
            raise ValueError(f"Obstacle.name: expected a non-empty string, got {self.name!r}")
        owner = f"Obstacle {self.name!r}"
        object.__setattr__(self, "position", check_vector3(self.position, owner, "position"))
        object.__setattr__(self, "radius", check_positive(self.radius, owner, "radius", " m"))

    @classmethod
    def from_box(cls, name: str, position: Sequence[float], extents: Sequence[float]) -> Obstacle:
        """Bound a box obstacle by the sphere through its corners.

        Parameters
        ----------
        name : str
            Name of the obstacle.
        position : sequence of float, shape (3,)
            Box centre in {W}, metres.
        extents : sequence of float, shape (3,)
            Full box sizes along its axes, metres.
        """
        sizes = check_vector3(extents, f"Obstacle {name!r}", "size")
        for i, size in enumerate(sizes):
            check_positive(size, f"Obstacle {name!r}", f"size[{i}]", " m")
        return cls(
            name,
            check_vector3(position, f"Obstacle {name!r}", "position"),
            0.5 * math.hypot(*sizes),
        )


@dataclass(frozen=True)
class ObjectContext:
    """The object to manipulate, its state, its surroundings and the task's goals.

    Attributes
    ----------
    name : str
        Name of the object in the world.
    category : str
        Free vocabulary matched by rules (``parcel``, ``bottle``, ``tray``); stored lower-case.
    shape : Shape
        Primitive that ``dimensions`` describes.
    dimensions : tuple of float
        Metres: box and mesh ``(x, y, z)`` full extents in the object frame {O};
        cylinder ``(radius, height)`` with its axis along z of {O}; sphere ``(radius,)``.
    mass_kg : float
        Mass, kilograms (> 0).
    material : str
        Free vocabulary matched by rules (``cardboard``, ``glass``); stored lower-case.
    friction : float
        Coulomb friction coefficient of the object's surface (>= 0).
    fragility : Fragility
        Whether it tolerates squeezing.
    state : frozenset of ObjectState
        State facts; ``open``/``closed`` and ``full``/``empty`` exclude each other.
    position : tuple of float, shape (3,)
        Object centre in {W}, metres.
    yaw : float
        Rotation of {O} about world z, radians.
    obstacles : tuple of Obstacle
        Surrounding objects and obstacles.
    goals : tuple of tuple of float, each shape (3,)
        Goal positions of the object centre in {W}, metres, in visiting order; may be empty.
    goal_yaw : float or None
        Yaw the object must have at the last goal, radians; ``None`` if free.
    goal_yaws : tuple of float
        Yaw at each goal of ``goals``, radians, in visiting order; may be empty (then only
        ``goal_yaw`` is known). Each move is planned with its own turn.
    goal_grasp_turns : tuple of float
        Turn about the grasp axis (the object's y axis, through a lateral grasp's palms) each
        move of ``goals`` makes, radians, in visiting order (:func:`skills.flip.grasp_axis_turn`
        from the previous goal's orientation); may be empty (no such turn).
    goal_fixtures : tuple of str
        The fixture each move of ``goals`` seats the object in ("" for none), in visiting
        order; may be empty (no move into a fixture).
    squeeze_axes : tuple of str
        A mesh: the axes of {O}, of ``"x"`` and ``"y"``, across which two sides of its hull
        hold a lateral squeeze (:mod:`worlds.mesh_sides`); empty for the other shapes, whose
        faces their dimensions give.
    """

    name: str
    category: str
    shape: Shape
    dimensions: tuple[float, ...]
    mass_kg: float
    material: str
    friction: float
    fragility: Fragility = Fragility.NORMAL
    state: frozenset[ObjectState] = field(default_factory=frozenset)
    position: Vector3 = (0.0, 0.0, 0.0)
    yaw: float = 0.0
    obstacles: tuple[Obstacle, ...] = ()
    goals: tuple[Vector3, ...] = ()
    goal_yaw: float | None = None
    goal_yaws: tuple[float, ...] = ()
    goal_grasp_turns: tuple[float, ...] = ()
    goal_fixtures: tuple[str, ...] = ()
    squeeze_axes: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name:
            raise ValueError(f"ObjectContext.name: expected a non-empty string, got {self.name!r}")
        owner = f"ObjectContext {self.name!r}"
        put = object.__setattr__
        put(self, "category", check_text(self.category, owner, "category"))
        put(self, "material", check_text(self.material, owner, "material"))
        shape = check_enum(self.shape, Shape, owner, "shape")
        put(self, "shape", shape)
        put(self, "dimensions", _check_dimensions(self.dimensions, shape, owner))
        put(self, "mass_kg", check_positive(self.mass_kg, owner, "mass_kg", " kg"))
        put(self, "friction", check_non_negative(self.friction, owner, "friction"))
        put(self, "fragility", check_enum(self.fragility, Fragility, owner, "fragility"))
        put(self, "state", _check_state(self.state, owner))
        put(self, "position", check_vector3(self.position, owner, "position"))
        put(self, "yaw", check_finite(self.yaw, owner, "yaw"))
        put(self, "obstacles", _check_obstacles(self.obstacles, owner))
        if isinstance(self.goals, str | bytes) or not isinstance(self.goals, Iterable):
            raise ValueError(f"{owner}.goals: expected a list of (x, y, z), got {self.goals!r}")
        goals = tuple(check_vector3(g, owner, f"goals[{i}]") for i, g in enumerate(self.goals))
        put(self, "goals", goals)
        if self.goal_yaw is not None:
            put(self, "goal_yaw", check_finite(self.goal_yaw, owner, "goal_yaw"))
        if isinstance(self.goal_yaws, str | bytes) or not isinstance(self.goal_yaws, Iterable):
            raise ValueError(
                f"{owner}.goal_yaws: expected a list of angles in rad, got {self.goal_yaws!r}"
            )
        put(
            self,
            "goal_yaws",
            tuple(check_finite(y, owner, f"goal_yaws[{i}]") for i, y in enumerate(self.goal_yaws)),
        )
        turns = self.goal_grasp_turns
        if isinstance(turns, str | bytes) or not isinstance(turns, Iterable):
            raise ValueError(
                f"{owner}.goal_grasp_turns: expected a list of angles in rad, got {turns!r}"
            )
        put(
            self,
            "goal_grasp_turns",
            tuple(check_finite(a, owner, f"goal_grasp_turns[{i}]") for i, a in enumerate(turns)),
        )
        fixtures = self.goal_fixtures
        if (
            isinstance(fixtures, str | bytes)
            or not isinstance(fixtures, Iterable)
            or not all(isinstance(f, str) for f in fixtures)
        ):
            raise ValueError(
                f"{owner}.goal_fixtures: expected a list of fixture names, got {fixtures!r}"
            )
        put(self, "goal_fixtures", tuple(fixtures))
        axes = self.squeeze_axes
        if isinstance(axes, str | bytes) or not all(a in ("x", "y") for a in axes):
            raise ValueError(f"{owner}.squeeze_axes: expected axes of x and y, got {axes!r}")
        put(self, "squeeze_axes", tuple(axes))


def _check_dimensions(value: Any, shape: Shape, owner: str) -> tuple[float, ...]:
    names = DIMENSION_NAMES[shape]
    if isinstance(value, str | bytes) or not isinstance(value, Iterable):
        raise ValueError(
            f"{owner}.dimensions: expected {shape.value} ({', '.join(names)}), got {value!r}"
        )
    items = list(value)
    if len(items) != len(names):
        raise ValueError(
            f"{owner}.dimensions: expected {len(names)} values for a {shape.value} "
            f"({', '.join(names)}), got {len(items)}: {items!r}"
        )
    return tuple(
        check_positive(v, owner, f"dimensions.{name}", " m")
        for v, name in zip(items, names, strict=True)
    )


def _check_state(value: Any, owner: str) -> frozenset[ObjectState]:
    if isinstance(value, str | bytes) or not isinstance(value, Iterable):
        raise ValueError(f"{owner}.state: expected a set of states, got {value!r}")
    state = frozenset(check_enum(v, ObjectState, owner, "state") for v in value)
    for a, b in _CONTRADICTIONS:
        if a in state and b in state:
            raise ValueError(f"{owner}.state: {a.value!r} and {b.value!r} exclude each other")
    return state


def _check_obstacles(value: Any, owner: str) -> tuple[Obstacle, ...]:
    if isinstance(value, str | bytes) or not isinstance(value, Iterable):
        raise ValueError(f"{owner}.obstacles: expected a list of Obstacle, got {value!r}")
    items = tuple(value)
    for i, item in enumerate(items):
        if not isinstance(item, Obstacle):
            raise ValueError(f"{owner}.obstacles[{i}]: expected an Obstacle, got {item!r}")
    names = [o.name for o in items]
    duplicates = sorted({n for n in names if names.count(n) > 1})
    if duplicates:
        raise ValueError(f"{owner}.obstacles: duplicate names {duplicates}")
    return items


@dataclass(frozen=True)
class RobotCapabilities:
    """What the dual-arm robot can carry and squeeze.

    Attributes
    ----------
    payload_per_arm_kg : float
        Mass one arm can carry, kilograms (> 0).
    palm_size_m : tuple of float, shape (3,)
        Palm ``(length, width, thickness)``, metres; the width is the one across the hand.
    max_span_m : float
        Largest distance between the two palms, metres.
    min_span_m : float
        Smallest distance between the two palms, metres (< ``max_span_m``).
    squeeze_force_n : float
        Normal force each palm can press with, newtons (>= 0).
    palm_friction : float
        Coulomb friction coefficient of the palm surface (>= 0).
    end_effectors : frozenset of EndEffector
        What the arms end in (at least one kind); it fixes which grasps the robot can make
        (:data:`affordances.physics.GRASP_END_EFFECTOR`).
    max_turn_rad : float
        Largest turn of the palms about the vertical from their natural pose that the arms can
        hold an object at, radians, in [pi/4, pi/2) (:mod:`skills.turns`: a larger turn of the
        object is made in steps, re-grasping between them).
    base_pose : tuple of float, shape (3,)
        The robot's frame in {W}: ``(x, y, heading)``, metres and radians (its +x forward,
        its +y to its left). The hard constraints are reasoned in that frame (which arm is on
        the object's side, which faces the palms come to); ``(0, 0, 0)``: {W} itself.
    """

    payload_per_arm_kg: float
    palm_size_m: Vector3
    max_span_m: float
    min_span_m: float
    squeeze_force_n: float
    palm_friction: float
    end_effectors: frozenset[EndEffector]
    max_turn_rad: float = math.pi / 4.0
    base_pose: Vector3 = (0.0, 0.0, 0.0)

    def __post_init__(self) -> None:
        owner = "RobotCapabilities"
        put = object.__setattr__
        put(
            self,
            "payload_per_arm_kg",
            check_positive(self.payload_per_arm_kg, owner, "payload_per_arm_kg", " kg"),
        )
        palm = check_vector3(self.palm_size_m, owner, "palm_size_m")
        for i, size in enumerate(palm):
            check_positive(size, owner, f"palm_size_m[{i}]", " m")
        put(self, "palm_size_m", palm)
        put(self, "max_span_m", check_positive(self.max_span_m, owner, "max_span_m", " m"))
        put(self, "min_span_m", check_non_negative(self.min_span_m, owner, "min_span_m"))
        if self.min_span_m >= self.max_span_m:
            raise ValueError(
                f"{owner}.min_span_m: expected < max_span_m = {self.max_span_m!r}, "
                f"got {self.min_span_m!r}"
            )
        put(
            self,
            "squeeze_force_n",
            check_non_negative(self.squeeze_force_n, owner, "squeeze_force_n"),
        )
        put(self, "palm_friction", check_non_negative(self.palm_friction, owner, "palm_friction"))
        put(self, "end_effectors", _check_end_effectors(self.end_effectors, owner))
        turn = check_finite(self.max_turn_rad, owner, "max_turn_rad")
        if not math.pi / 4.0 - 1e-9 <= turn < math.pi / 2.0:
            raise ValueError(
                f"{owner}.max_turn_rad: expected an angle in [pi/4, pi/2) rad, got {turn!r}"
            )
        put(self, "max_turn_rad", turn)
        put(self, "base_pose", check_vector3(self.base_pose, owner, "base_pose"))

    def describe_end_effectors(self) -> str:
        """The end-effectors in words, e.g. ``flat palms``."""
        return " and ".join(_END_EFFECTOR_WORDS[e] for e in sorted(self.end_effectors))

    @property
    def palm_width_m(self) -> float:
        """Width across the palm, metres."""
        return self.palm_size_m[1]


_END_EFFECTOR_WORDS = {EndEffector.FLAT_PALM: "flat palms", EndEffector.GRIPPER: "grippers"}


def _check_end_effectors(value: Any, owner: str) -> frozenset[EndEffector]:
    if isinstance(value, str | bytes) or not isinstance(value, Iterable):
        raise ValueError(f"{owner}.end_effectors: expected a set of end-effectors, got {value!r}")
    kinds = frozenset(check_enum(v, EndEffector, owner, "end_effectors") for v in value)
    if not kinds:
        raise ValueError(f"{owner}.end_effectors: expected at least one end-effector, got none")
    return kinds


#: The robot of the paper's parcel experiment, as given in the project brief.
PAPER_ROBOT = RobotCapabilities(
    payload_per_arm_kg=7.0,
    palm_size_m=(0.12, 0.09, 0.02),
    max_span_m=0.6,
    min_span_m=0.15,
    squeeze_force_n=40.0,
    palm_friction=0.8,
    end_effectors=frozenset({EndEffector.FLAT_PALM}),
)


def _obstacle_from_plain(value: Any, index: int) -> Obstacle:
    if isinstance(value, Obstacle):
        return value
    if not isinstance(value, Mapping):
        raise ValueError(f"obstacles[{index}]: expected a mapping or Obstacle, got {value!r}")
    keys = set(value)
    allowed = {"name", "position", "radius", "size"}
    if keys - allowed:
        raise ValueError(
            f"obstacles[{index}]: unknown keys {sorted(keys - allowed)}; allowed {sorted(allowed)}"
        )
    if "name" not in value or "position" not in value:
        raise ValueError(
            f"obstacles[{index}]: expected keys 'name' and 'position', got {sorted(keys)}"
        )
    if ("radius" in value) == ("size" in value):
        raise ValueError(
            f"obstacles[{index}] {value['name']!r}: expected exactly one of 'radius' or 'size'"
        )
    if "size" in value:
        return Obstacle.from_box(value["name"], value["position"], value["size"])
    return Obstacle(value["name"], value["position"], value["radius"])


def make_object_context(
    name: str,
    category: str,
    shape: str | Shape,
    dimensions: Sequence[float],
    mass_kg: float,
    material: str,
    friction: float,
    fragility: str | Fragility = Fragility.NORMAL,
    state: Iterable[str | ObjectState] = (),
    position: Sequence[float] = (0.0, 0.0, 0.0),
    yaw: float = 0.0,
    obstacles: Iterable[Mapping[str, Any] | Obstacle] = (),
    goals: Iterable[Sequence[float]] = (),
    goal_yaw: float | None = None,
) -> ObjectContext:
    """Build an :class:`ObjectContext` from plain values (strings, lists, dicts).

    Parameters are those of :class:`ObjectContext`, as plain values: enum values as strings
    (``"box"``, ``"fragile"``, ``["open", "full"]``), vectors as lists. ``obstacles`` are
    mappings with ``name``, ``position`` (3,) and either ``radius`` (m, a sphere) or
    ``size`` (m, box extents (3,), bounded by the sphere through its corners).

    Parameters
    ----------
    name, category, material : str
        Object name and the free vocabulary rules match.
    shape : str or Shape
        ``box``, ``cylinder``, ``sphere`` or ``mesh``.
    dimensions : sequence of float
        Metres; see :class:`ObjectContext`.
    mass_kg, friction : float
        Kilograms; Coulomb coefficient.
    fragility : str or Fragility
        ``robust``, ``normal`` or ``fragile``.
    state : iterable of str or ObjectState
        State facts.
    position : sequence of float, shape (3,)
        Object centre in {W}, metres.
    yaw : float
        Radians about world z.
    obstacles : iterable of mapping or Obstacle
        Surrounding objects.
    goals : iterable of sequence of float, each shape (3,)
        Goal positions in {W}, metres.
    goal_yaw : float or None
        Yaw at the last goal, radians.

    Returns
    -------
    ObjectContext
        The validated context; raises ``ValueError`` naming the first bad field.
    """
    if isinstance(state, str):
        state = (state,)
    return ObjectContext(
        name=name,
        category=category,
        shape=check_enum(shape, Shape, f"ObjectContext {name!r}", "shape"),
        dimensions=tuple(dimensions),
        mass_kg=mass_kg,
        material=material,
        friction=friction,
        fragility=check_enum(fragility, Fragility, f"ObjectContext {name!r}", "fragility"),
        state=frozenset(
            check_enum(s, ObjectState, f"ObjectContext {name!r}", "state") for s in state
        ),
        position=check_vector3(position, f"ObjectContext {name!r}", "position"),
        yaw=yaw,
        obstacles=tuple(_obstacle_from_plain(o, i) for i, o in enumerate(obstacles)),
        goals=tuple(
            check_vector3(g, f"ObjectContext {name!r}", f"goals[{i}]") for i, g in enumerate(goals)
        ),
        goal_yaw=goal_yaw,
    )
