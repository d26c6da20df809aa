"""The world file's ``trials`` section: where ``app.py trials`` draws each trial.

The regions the object's start and goals are drawn in (:class:`Region`, :class:`GoalRegion`),
the obstacle spheres' ranges, Hard mode's ranges of the physical truth (:class:`HardSettings`)
and the balls riding on a tray (:class:`RiderTrials`), gathered in :class:`TrialSettings`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Annotated, Any

from pydantic import (
    Field,
    SerializerFunctionWrapHandler,
    field_validator,
    model_serializer,
    model_validator,
)

from worlds.fixture_schema import InsertionTrials
from worlds.schema_types import FileModel, Finite, NonNegative, OptionalRange, Range
from worlds.spec import ObstacleKind
from worlds.world_errors import Shown, field_problem

#: Most a Hard table may stand off its file height, m: Approach takes an object that lies more
#: than 5 cm below the stated top for one fallen off the table (planner.leaves.approach's
#: OFF_TABLE_M), so a lower table fails every trial by construction.
TABLE_DZ_LIMIT_M = 0.05


class Region(FileModel):
    """A rectangle of the table where an object's centre is drawn."""

    x: Range = Field(description="[low, high] of the centre's x, world frame, m")
    y: Range = Field(description="[low, high] of the centre's y, world frame, m")


def _yaw_in_a_turn(yaw: tuple[float, float] | None) -> tuple[float, float] | None:
    # One turn at most, anywhere in [-360, 360]: [90, 270] is the yaws a robot facing -x
    # holds as one facing +x holds [-90, 90].
    if yaw is not None and (yaw[0] < -360.0 or yaw[1] > 360.0 or yaw[1] - yaw[0] > 360.0):
        raise field_problem(
            "angles within [-360, 360] degrees spanning at most one turn (360 degrees)", yaw
        )
    return yaw


#: Every kind of obstacle sphere, in the order a trial draws between them.
OBSTACLE_KINDS = (ObstacleKind.LINE, ObstacleKind.AHEAD)


class GoalRegion(Region):
    """One move of a trial: where its goal's centre is drawn, the goal's yaw and the kinds of
    obstacle sphere the move may get."""

    yaw_deg: OptionalRange = Field(
        default=None,
        description="[low, high] of the goal's yaw about z, degrees, within [-360, 360] and "
        "one turn (e.g. [90, 270] for a robot facing -x); default: trials.goal_yaw_deg",
    )
    obstacles: tuple[ObstacleKind, ...] = Field(
        default=OBSTACLE_KINDS,
        description="kinds of sphere this move's obstacle is drawn as (line: over the "
        "straight path, under the lift; ahead: in front of the carry, along the robot's forward "
        "axis, +x for a robot facing +x); [] for none",
    )

    pitch_deg: tuple[Finite, ...] = Field(
        default=(),
        description="pitches the goal is drawn from, one with equal chance, degrees, each -90, "
        "0 or 90: a turn about the box's y axis (the palms' axis) that sets it down on its "
        "side; default: upright",
    )

    _yaw = field_validator("yaw_deg")(_yaw_in_a_turn)

    @field_validator("pitch_deg")
    @classmethod
    def _quarter_turns(cls, pitches: tuple[float, ...]) -> tuple[float, ...]:
        if any(p not in (-90.0, 0.0, 90.0) for p in pitches):
            raise field_problem("pitches of -90, 0 or 90 degrees", pitches)
        return pitches

    @field_validator("obstacles")
    @classmethod
    def _each_kind_once(cls, kinds: tuple[ObstacleKind, ...]) -> tuple[ObstacleKind, ...]:
        if len(set(kinds)) != len(kinds):
            raise field_problem("each kind at most once", kinds)
        return kinds


def _range_at_least(low: float, strict: bool, what: str) -> Any:
    """A validator of a :data:`Range` whose low end is above ``low`` (``strict``) or at it."""

    def check(bounds: tuple[float, float]) -> tuple[float, float]:
        if bounds[0] < low or (strict and bounds[0] == low):
            raise field_problem(what, bounds)
        return bounds

    return check


#: Default range of a fixture's true offset from its file place, m (Hard mode): a little over
#: its usual 5 mm clearance, so the carry may come down on a wall's top.
FIXTURE_OFFSET_M = (0.0, 0.008)


class HardSettings(FileModel):
    """How ``app.py trials --hard`` draws each trial's physical truth: the physics differs from
    what the robot is told by values drawn from these ranges (uniform unless said otherwise),
    from the campaign seed and the trial's index alone."""

    mass_scale: Range = Field(
        default=(0.5, 1.5), description="the object's true mass over its file mass, > 0"
    )
    friction_scale: Range = Field(
        default=(0.7, 1.3), description="the object's true friction over its file one, >= 0"
    )
    palm_friction_scale: Range = Field(
        default=(0.8, 1.2), description="the palms' true friction over their model's, >= 0"
    )
    table_dz_m: Range = Field(
        default=(-0.03, 0.03),
        description="the table top's true height less the file's, m; the object starts on it",
    )
    fixture_offset_m: Range = Field(
        default=FIXTURE_OFFSET_M,
        description="how far each fixture truly stands from its file place, m, 0 to 0.1, in "
        "a direction uniform on the table (the robot finds its walls by touch)",
    )
    pose_sigma_m: Annotated[float, Field(strict=True, allow_inf_nan=False, ge=0, le=1)] = Field(
        default=0.005,
        description="standard deviation of the sensed start position's error along x and y "
        "(normal), m, 0 to 1",
    )
    yaw_sigma_deg: Annotated[float, Field(strict=True, allow_inf_nan=False, ge=0, le=180)] = Field(
        default=2.0,
        description="standard deviation of the sensed start yaw's error (normal), degrees, "
        "0 to 180",
    )
    push_rate_hz: Annotated[float, Field(strict=True, allow_inf_nan=False, ge=0, le=10)] = Field(
        default=0.2,
        description="mean pushes per second of simulated time on each object (Poisson), 0 to 10",
    )
    push_force_n: Range = Field(
        default=(5.0, 20.0),
        description="a push's force, N, >= 0, in a direction uniform on the sphere",
    )
    push_duration_s: Range = Field(default=(0.05, 0.2), description="a push's length, s, > 0")
    torque_scale: Range = Field(
        default=(0.85, 1.15), description="each joint's applied torque over its computed, > 0"
    )
    torque_bias: Annotated[float, Field(strict=True, allow_inf_nan=False, ge=0, le=1)] = Field(
        default=0.03,
        description="each joint's torque bias is drawn within +- this fraction of its torque "
        "limit, 0 to 1",
    )
    torque_lag_s: Range = Field(
        default=(0.01, 0.03),
        description="time constant of the first-order lag on the applied torques, s, >= 0",
    )
    latency_ticks: Annotated[int, Field(strict=True, ge=0, le=100)] = Field(
        default=1,
        description="physics steps between reading the joint state and applying the torque "
        "computed from it, 0 to 100",
    )

    _positive = field_validator("mass_scale", "torque_scale", "push_duration_s")(
        _range_at_least(0.0, True, "values > 0")
    )
    _non_negative = field_validator(
        "friction_scale", "palm_friction_scale", "push_force_n", "torque_lag_s"
    )(_range_at_least(0.0, False, "values >= 0"))

    @model_serializer(mode="wrap")
    def _as_before_fixtures(self, handler: SerializerFunctionWrapHandler) -> Any:
        # A hard section that leaves the fixtures' offset at its default dumps as it did before
        # the field existed: a world's content hash names its campaigns (experiment.records).
        data = handler(self)
        if isinstance(data, dict) and self.fixture_offset_m == FIXTURE_OFFSET_M:
            data.pop("fixture_offset_m", None)
        return data

    @field_validator("fixture_offset_m")
    @classmethod
    def _within_a_decimetre(cls, offset: tuple[float, float]) -> tuple[float, float]:
        if offset[0] < 0.0 or offset[1] > 0.1:
            raise field_problem("distances within [0, 0.1] m", offset)
        return offset

    @field_validator("table_dz_m")
    @classmethod
    def _within_what_the_robot_takes_for_its_table(
        cls, dz: tuple[float, float]
    ) -> tuple[float, float]:
        if dz[0] < -TABLE_DZ_LIMIT_M or dz[1] > TABLE_DZ_LIMIT_M:
            raise field_problem(
                f"heights within [-{TABLE_DZ_LIMIT_M:g}, {TABLE_DZ_LIMIT_M:g}] m (an object "
                f"more than {TABLE_DZ_LIMIT_M * 100:g} cm below where the file puts it reads "
                "to the robot as fallen off its table: every such trial would fail)",
                dz,
            )
        return dz


def _fraction_of_room(bounds: tuple[float, float] | None) -> tuple[float, float] | None:
    if bounds is not None and (bounds[0] < -1.0 or bounds[1] > 1.0):
        raise field_problem("fractions within [-1, 1]", bounds)
    return bounds


class RiderTrials(FileModel):
    """How ``app.py trials`` draws the balls loose on a tray (``objects[0]``,
    :func:`worlds.trays.riders`): where each starts on the floor, its radius and its mass.

    A start is a fraction, per axis of the tray's frame, of how far the ball's centre can go
    from the tray's centre with ``wall_gap`` m left to the walls (-1 and 1: that close to
    the -x or +x wall), so every start lies inside whatever tray the trial draws.
    """

    x: OptionalRange = Field(
        default=None,
        description="[low, high] of the ball's start along the tray's x, a fraction of its "
        "room, within [-1, 1]; default: the file's place (the same fraction of the room)",
    )
    y: OptionalRange = Field(
        default=None,
        description="[low, high] of the ball's start along the tray's y, a fraction of its "
        "room, within [-1, 1]; default: the file's place (the same fraction of the room)",
    )
    radius_scale: OptionalRange = Field(
        default=None,
        description="[low, high] of a factor the ball's radius is scaled by, > 0; "
        "default: the file's radius",
    )
    mass_kg: OptionalRange = Field(
        default=None, description="[low, high] of the ball's mass, kg, > 0; default: the file's"
    )
    wall_gap: NonNegative = Field(
        default=0.005, description="least gap between the ball and a wall at its start, m"
    )

    _fraction = field_validator("x", "y")(_fraction_of_room)

    @field_validator("radius_scale", "mass_kg")
    @classmethod
    def _positive_or_none(cls, bounds: tuple[float, float] | None) -> tuple[float, float] | None:
        if bounds is not None and bounds[0] <= 0.0:
            raise field_problem("values > 0", bounds)
        return bounds


class TrialSettings(FileModel):
    """How ``app.py trials`` draws the paper's experiment in this world.

    The workspace depends on the robot, so the world says where the object starts, where its
    goals lie and how the obstacle spheres are drawn. The goals are either the paper's three,
    ``centre``, ``right`` (-y) and ``left`` (+y), or any number of ``moves``, each a
    :class:`GoalRegion` (not both). The defaults suit the default two-iiwa world.
    """

    start: Region = Field(
        default=Region(x=(0.50, 0.60), y=(-0.04, 0.04)), description="the object's start"
    )
    centre: Region = Field(
        default=Region(x=(0.58, 0.68), y=(-0.03, 0.03)), description="the first goal"
    )
    right: Region = Field(
        default=Region(x=(0.55, 0.65), y=(-0.18, -0.12)), description="the second goal (-y)"
    )
    left: Region = Field(
        default=Region(x=(0.55, 0.65), y=(0.12, 0.18)), description="the third goal (+y)"
    )
    sphere_radius: Range = Field(default=(0.03, 0.05), description="obstacle radius, m, > 0")
    line_gap: Range = Field(
        default=(0.03, 0.06),
        description="a sphere on the line: its bottom above the object's top, m",
    )
    ahead_gap: Range = Field(
        default=(0.0, 0.04),
        description="a sphere ahead: its surface in front of the object's front face (along the "
        "robot's forward axis), m",
    )
    ahead_height: Range = Field(
        default=(-0.02, 0.06),
        description="a sphere ahead: its centre above the object's top, m",
    )
    clearance: NonNegative = Field(
        default=0.02,
        description="least gap between a sphere and the object at its move's start and goal, m",
    )
    robot_clearance: NonNegative = Field(
        default=0.05,
        description="least gap between a sphere and the robot grasping the object at its "
        "move's start and goal, m",
    )
    lift: NonNegative = Field(
        default=0.03,
        description="the robot_clearance holds also with the object lifted this much at the "
        "start and the goal (a carry begins with a lift and ends with a lowering), m",
    )
    goal_yaw_deg: Range = Field(
        default=(0.0, 0.0),
        description="[low, high] of each goal's yaw about z, degrees, within [-360, 360] and "
        "one turn (e.g. [90, 270] for a robot facing -x; a move's own yaw_deg replaces it)",
    )
    moves: tuple[GoalRegion, ...] = Field(
        default=(),
        min_length=1,
        description="each move's goal region, in order, at least 1; without it the three "
        "moves centre, right and left",
    )
    hard: HardSettings = Field(
        default_factory=HardSettings,
        description="with --hard, how each trial's physics is drawn to differ from the file",
    )
    size_scale: OptionalRange = Field(
        default=None,
        description="[low, high] of a factor each trial scales the object's box extents by "
        "(one factor per axis), > 0; a tray's height never below the least the palms need "
        "(experiment.tray_draws) or the file's; default: the file's size",
    )
    mass_kg: OptionalRange = Field(
        default=None, description="[low, high] of the object's mass, kg, > 0; default: the file's"
    )

    @field_validator("size_scale", "mass_kg")
    @classmethod
    def _positive_or_none(cls, bounds: tuple[float, float] | None) -> tuple[float, float] | None:
        if bounds is not None and bounds[0] <= 0.0:
            raise field_problem("values > 0", bounds)
        return bounds

    insertion: InsertionTrials | None = Field(
        default=None,
        description="where a trial draws a fixture (and the box it fits); default: as is",
    )
    riders: RiderTrials | None = Field(
        default=None,
        description="how a trial draws the balls loose on a tray (objects[0]); default: "
        "each where the file puts it on the tray, its own radius and mass",
    )

    @field_validator("sphere_radius")
    @classmethod
    def _radius_positive(cls, radius: tuple[float, float]) -> tuple[float, float]:
        if radius[0] <= 0.0:
            raise field_problem("radii > 0", radius)
        return radius

    _yaw = field_validator("goal_yaw_deg")(_yaw_in_a_turn)

    @model_validator(mode="after")
    def _one_form_of_goals(self) -> TrialSettings:
        named = [k for k in PAPER_REGIONS if k in self.model_fields_set]
        if self.moves and named:
            raise field_problem(
                "either moves or the regions centre, right and left, not both",
                Shown(f"{named[0]} beside moves ({len(self.moves)})"),
                named[0],
            )
        return self

    def goal_regions(self) -> tuple[GoalRegion, ...]:
        """Each move's goal region, in order, its ``yaw_deg`` given (``goal_yaw_deg`` unless
        the move has its own): ``moves``, or the paper's centre, right and left."""
        regions = self.moves or tuple(
            GoalRegion(x=r.x, y=r.y) for r in (self.centre, self.right, self.left)
        )
        return tuple(
            r if r.yaw_deg is not None else r.model_copy(update={"yaw_deg": self.goal_yaw_deg})
            for r in regions
        )

    @model_serializer(mode="wrap")
    def _as_before(self, handler: SerializerFunctionWrapHandler) -> Any:
        # Settings without a hard section or moves dump as before those existed: a world's
        # content hash names its trial campaigns (experiment.records), and those must stay
        # its own. With moves, the unused paper regions are left out (they are defaults).
        data = handler(self)
        if isinstance(data, dict):
            if self.hard == HardSettings():
                data.pop("hard", None)
            if self.insertion is None:
                data.pop("insertion", None)
            if self.riders is None:
                data.pop("riders", None)
            for key in ("moves",) if not self.moves else PAPER_REGIONS:
                data.pop(key, None)
            for key in ("size_scale", "mass_kg"):
                if data.get(key) is None:
                    data.pop(key, None)
            for move in data.get("moves", ()):
                if isinstance(move, dict) and not move.get("pitch_deg"):
                    move.pop("pitch_deg", None)
        return data


#: The paper's three goal regions, in the order of its moves.
PAPER_REGIONS = ("centre", "right", "left")


def trials_in_robot_frame(position: Sequence[float], yaw_deg: float) -> dict[str, Any]:
    """The default ``trials`` section (:class:`TrialSettings`'s, made for a robot at the
    origin facing +x) for a robot standing at ``position`` (m, world frame) turned ``yaw_deg``
    about z, as world-file data: each region turned and moved with the robot (the rectangle
    that holds its corners: the same size for a quarter turn, larger between), the goals'
    yaw turned with it; empty for a robot at the origin facing +x, whose defaults they are. A
    world that gives no ``trials`` section gets these."""
    if tuple(position[:2]) == (0.0, 0.0) and yaw_deg % 360.0 == 0.0:
        return {}
    defaults = TrialSettings()
    c, s = math.cos(math.radians(yaw_deg)), math.sin(math.radians(yaw_deg))

    def placed(region: Region) -> dict[str, list[float]]:
        corners = [
            (x * c - y * s + position[0], x * s + y * c + position[1])
            for x in region.x
            for y in region.y
        ]
        xs, ys = [round(p[0], 9) for p in corners], [round(p[1], 9) for p in corners]
        return {"x": [min(xs), max(xs)], "y": [min(ys), max(ys)]}

    low, high = defaults.goal_yaw_deg
    turn = (yaw_deg + 180.0) % 360.0 - 180.0  # within a turn, as the file's yaws must be
    return {
        **{name: placed(getattr(defaults, name)) for name in ("start", *PAPER_REGIONS)},
        "goal_yaw_deg": [low + turn, high + turn],
    }


__all__ = [
    "FIXTURE_OFFSET_M",
    "OBSTACLE_KINDS",
    "PAPER_REGIONS",
    "GoalRegion",
    "HardSettings",
    "Region",
    "RiderTrials",
    "TrialSettings",
    "trials_in_robot_frame",
]
