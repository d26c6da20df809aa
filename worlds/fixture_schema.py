"""The world file's fixtures: open boxes on the table an object is inserted into.

A fixture is made for one object (``for_object``, a box): its inside is that box's footprint
plus ``clearance`` m per side, so a trial that draws another box size draws a fitting
fixture. Its walls stand on the table top (the fixture's floor), ``wall_height`` m tall and
``wall_thickness`` m thick, around a centre ``position`` [x, y] turned ``yaw_deg`` about z.

A move names the fixture it seats its object in (``task[].moves[].fixture``); its goal must
then be the seated pose: the fixture's centre, the box's bottom on the table, turned as the
fixture (or half a turn from it). Checked here against the rest of the world
(:func:`fixture_issues`), as the world's other cross-references are.

The walls must stay below the palms holding the seated box: the palms go up the faces by
:func:`skills.insertion.grasp_height`, which clears walls up to
:func:`skills.insertion.max_wall_height` (from the box's height and the palms' length).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Annotated, Any

from pydantic import BaseModel, BeforeValidator, ConfigDict, Field

from worlds.world_errors import Issue, field_problem, show_value

#: How far a fixture move's goal may be from the seated pose: m and degrees.
SEATED_GOAL_TOLERANCE_M = 1e-3
SEATED_GOAL_TOLERANCE_DEG = 0.5

_Metres = Annotated[float, Field(strict=True, allow_inf_nan=False, ge=-100.0, le=100.0)]
_Positive = Annotated[float, Field(strict=True, allow_inf_nan=False, gt=0.0, le=100.0)]
_NonNegative = Annotated[float, Field(strict=True, allow_inf_nan=False, ge=0.0, le=1e6)]
_Degrees = Annotated[float, Field(strict=True, allow_inf_nan=False, ge=-180.0, le=180.0)]
_Name = Annotated[str, Field(strict=True, min_length=1)]


def _pair(value: Any) -> Any:
    if isinstance(value, str | bytes) or not isinstance(value, Sequence) or len(value) != 2:
        raise field_problem("a list of exactly 2 numbers", value)
    return tuple(value)


def _ordered(value: Any) -> Any:
    value = _pair(value)
    if all(isinstance(v, int | float) and not isinstance(v, bool) for v in value):
        if value[0] > value[1]:
            raise field_problem("low <= high", value)
    return value


Position2 = Annotated[tuple[_Metres, _Metres], BeforeValidator(_pair)]
"""Two numbers ``[x, y]``, m."""
MetreRange = Annotated[tuple[_Metres, _Metres], BeforeValidator(_ordered)]
"""Two numbers ``[low, high]``, m, low <= high."""
DegreeRange = Annotated[tuple[_Degrees, _Degrees], BeforeValidator(_ordered)]
"""Two angles ``[low, high]`` within [-180, 180] degrees, low <= high."""


class _Model(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class Fixture(_Model):
    """An open box on the table: four walls around a slot made for one object."""

    name: _Name = Field(description="unique name (across objects, obstacles and fixtures)")
    for_object: _Name = Field(
        description="the box object it is made for: its inside is that box's footprint "
        "plus clearance per side"
    )
    position: Position2 = Field(description="centre of the inside [x, y] on the table top, m")
    yaw_deg: _Degrees = Field(default=0.0, description="turn about z, degrees, [-180, 180]")
    clearance: _Positive = Field(
        default=0.005, description="gap between the box and each wall's inner face, m, > 0"
    )
    wall_thickness: _Positive = Field(default=0.02, description="m, > 0")
    wall_height: _Positive = Field(description="m above the table top, > 0")
    friction: _NonNegative = Field(default=0.3, description="friction of the walls, >= 0")


class BoxSizeRange(_Model):
    """Ranges a trial draws a box's extents from, m."""

    x: MetreRange
    y: MetreRange
    z: MetreRange


class InsertionTrials(_Model):
    """How ``app.py trials`` draws an insertion: where the fixture stands, how it is turned and
    (optionally) the box's size; the fixture always fits the box drawn."""

    fixture: str = Field(description="the fixture whose place is drawn")
    x: MetreRange = Field(description="[low, high] of the fixture's centre x, m")
    y: MetreRange = Field(description="[low, high] of the fixture's centre y, m")
    yaw_deg: DegreeRange = Field(default=(0.0, 0.0), description="the fixture's yaw, degrees")
    box_size: BoxSizeRange | None = Field(
        default=None, description="[low, high] of the box's x, y, z extents, m; default: as is"
    )


def fixture_issues(world: Any) -> list[Issue]:
    """Problems of ``world``'s fixtures against the rest of it (a validated
    :class:`worlds.world_schema.World`'s fields): names, the object each is made for, its
    place on the table, its walls against the palms, and the moves that name one."""
    from skills.insertion import max_wall_height  # lazily: validating needs no numpy

    issues: list[Issue] = []
    fixtures = tuple(world.fixtures)
    taken = {o.name for o in world.objects} | {o.name for o in world.obstacles}
    by_name: dict[str, Any] = {}
    objects = {o.name: o for o in world.objects}
    table = world.table
    palm_length = float(world.robot.palm_size[0])
    for i, f in enumerate(fixtures):
        if f.name in taken or f.name in by_name:
            issues.append(
                Issue(("fixtures", i, "name"), "a name not already used", show_value(f.name))
            )
            continue
        by_name[f.name] = f
        obj = objects.get(f.for_object)
        if obj is None or obj.shape.type.value != "box":
            what = "no such object" if obj is None else f"a {obj.shape.type.value}"
            issues.append(
                Issue(
                    ("fixtures", i, "for_object"),
                    f"the name of a box object ({', '.join(sorted(objects))})",
                    f"{f.for_object!r} ({what})",
                )
            )
            continue
        size = obj.shape.size
        highest = max_wall_height(size[2], palm_length)
        if f.wall_height > highest:
            issues.append(
                Issue(
                    ("fixtures", i, "wall_height"),
                    f"at most {highest:.3f} m: the palms ({palm_length:g} m long) holding "
                    f"{obj.name!r} ({size[2]:g} m tall) seated must stay above the walls",
                    show_value(f.wall_height),
                )
            )
        outer_x = size[0] + 2 * (f.clearance + f.wall_thickness)
        outer_y = size[1] + 2 * (f.clearance + f.wall_thickness)
        c, s = abs(math.cos(math.radians(f.yaw_deg))), abs(math.sin(math.radians(f.yaw_deg)))
        half = ((c * outer_x + s * outer_y) / 2, (s * outer_x + c * outer_y) / 2)
        for k in range(2):
            lo = table.position[k] - table.size[k] / 2
            hi = table.position[k] + table.size[k] / 2
            if f.position[k] - half[k] < lo or f.position[k] + half[k] > hi:
                issues.append(
                    Issue(
                        ("fixtures", i, "position"),
                        f"the fixture's outside within the table top ({'xy'[k]} {lo:g}..{hi:g})",
                        show_value(f.position),
                    )
                )
                break
    for s_i, step in enumerate(world.task):
        for m, move in enumerate(step.moves):
            if move.fixture is None:
                continue
            path = ("task", s_i, "moves", m, "fixture")
            f = by_name.get(move.fixture)
            if f is None or f.for_object != step.object:
                names = [x.name for x in fixtures if x.for_object == step.object]
                issues.append(
                    Issue(
                        path,
                        f"the name of a fixture made for {step.object!r} "
                        f"({', '.join(map(repr, names)) or 'there are none'})",
                        show_value(move.fixture),
                    )
                )
                continue
            obj = objects[step.object]
            seated = (*f.position, table.position[2] + obj.shape.size[2] / 2)
            off = math.dist(seated, move.goal.position)
            roll, pitch, yaw = move.goal.rpy_deg
            turn = (yaw - f.yaw_deg) % 180.0
            turn = min(turn, 180.0 - turn)
            tol = SEATED_GOAL_TOLERANCE_DEG
            if off > SEATED_GOAL_TOLERANCE_M or turn > tol or abs(roll) > tol or abs(pitch) > tol:
                issues.append(
                    Issue(
                        ("task", s_i, "moves", m, "goal"),
                        f"the pose seated in fixture {f.name!r}: position "
                        f"[{seated[0]:.4g}, {seated[1]:.4g}, {seated[2]:.4g}], "
                        f"rpy_deg [0, 0, {f.yaw_deg:g}] (or half a turn from it)",
                        show_value(
                            {"position": list(move.goal.position), "rpy_deg": [roll, pitch, yaw]}
                        ),
                    )
                )
    trials = world.trials.insertion
    if trials is not None and trials.fixture not in by_name:
        issues.append(
            Issue(
                ("trials", "insertion", "fixture"),
                f"the name of a fixture ({', '.join(map(repr, by_name)) or 'there are none'})",
                show_value(trials.fixture),
            )
        )
    return issues


__all__ = ["BoxSizeRange", "Fixture", "InsertionTrials", "fixture_issues"]
