"""Are a world's trial regions on its table and within the arms' reach? Checked before a
campaign.

``app.py trials`` draws each trial's start and goals from the world's ``trials`` regions
(:mod:`worlds.trial_schema`), in the world frame. A world that gives none gets the defaults
placed where its robot stands (:func:`worlds.trial_schema.trials_in_robot_frame`), which suit
a table laid out as the default world's (its top 0.35 to 0.95 m in front of the robot): on
another table they may lie off it, and every trial would fail at its first approach.
:func:`region_problems` runs the world's own checks (:func:`worlds.feasibility.goal_checker`:
a goal over the table top and a grasp within the arms' reach) on the object placed at each
corner of each region, at the ends and middle of its yaw range, so that a region fails here
if any part of it could fail a trial.
"""

from __future__ import annotations

from worlds.feasibility import goal_checker
from worlds.trial_schema import PAPER_REGIONS, Region, TrialSettings, trials_in_robot_frame
from worlds.world_file import World, as_world_spec


def _region_fields(world: World) -> list[str]:
    """The world file's field of each goal region, in move order."""
    layout = world.trials
    if layout.moves:
        return [f"trials.moves[{j}]" for j in range(len(layout.moves))]
    return [f"trials.{name}" for name in PAPER_REGIONS]


def region_problems(world: World) -> list[str]:
    """Why the world's trial regions cannot hold the object: one line per region that puts it
    off the table or out of the arms' reach at some corner (naming the field, the corner and
    the world check's reason); empty when every corner passes.

    The object is ``objects[0]`` at the file's size, upright; the start region is checked at
    the file's yaw, each goal region at its yaw range's ends and middle. What else a draw
    may meet (an object standing there, a fixture's walls) is drawn around, not refused.
    """
    layout = world.trials
    regions = layout.goal_regions()
    name = world.objects[0].name
    goal_problem = goal_checker(as_world_spec(world), name)
    start_yaw = float(world.objects[0].pose.rpy_deg[2])
    checked: list[tuple[str, Region, tuple[float, ...]]] = [
        ("trials.start", layout.start, (start_yaw,))
    ]
    for field, goal in zip(_region_fields(world), regions, strict=True):
        low, high = goal.yaw_deg or (0.0, 0.0)
        checked.append((field, goal, tuple(dict.fromkeys((low, 0.5 * (low + high), high)))))
    problems = []
    for field, region, yaws in checked:
        why = next(
            (
                (x, y, yaw, problem)
                for x in region.x
                for y in region.y
                for yaw in yaws
                if (problem := goal_problem((x, y), yaw)) is not None
            ),
            None,
        )
        if why is not None:
            x, y, yaw, (_, received) = why
            problems.append(
                f"{field}: expected a region where {name} stands over the table and within the "
                f"arms' reach at every corner, got the corner [{x:g}, {y:g}] at yaw {yaw:g} "
                f"deg: {received}"
            )
    if problems and layout == _defaults_of(world):
        problems.append(
            "trials: this world gives no trials section, so the defaults apply, placed where "
            "its robot stands and turned with it (they suit the default world's table, 0.35 to "
            "0.95 m in front of the robot); give regions on this world's table (app.py schema "
            "shows the section)"
        )
    return problems


def _defaults_of(world: World) -> TrialSettings:
    """The trials section a world of this robot gets when it gives none
    (:func:`worlds.trial_schema.trials_in_robot_frame`)."""
    base = world.robot.base
    return TrialSettings.model_validate(trials_in_robot_frame(base.position, base.rpy_deg[2]))


__all__ = ["region_problems"]
