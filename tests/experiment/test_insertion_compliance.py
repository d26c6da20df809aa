"""The insertion's force coupling where it must act: a fixture that stands off its file place.

Without physics: the search's formulas on known cases, the fixture's offset in the truth and
in Hard mode's draws, and the reasoner's plan for a move into a fixture. With physics: the
slot 7 mm off (more than its 5 mm clearance) along x, where the box's bottom edge comes down
on a wall's top, seated with the coupling and not without it.
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest
from numpy.testing import assert_allclose

from experiment.hard import draw_hard
from experiment.insertion import SEATED_TOLERANCE_DEG, SEATED_TOLERANCE_M, WALL_FORCE_LIMIT_S
from skills.insertion import (
    AdmittanceGains,
    admittance_step,
    bearing_point,
    descent_rate,
    felt_force,
    search_velocity,
)
from skills.vocabulary import Action, AffordanceElement
from worlds.truth import FixtureTruth, PhysicalTruth, physical_scene
from worlds.world_file import load_world, world_from_data, world_spec

SLOT = Path(__file__).resolve().parents[2] / "worlds" / "slot_insertion.yaml"
GAINS = AdmittanceGains(1e-3, 0.3, 5.0, 15.0, search_speed=0.005, max_shift=0.02)


def test_the_bearing_point_is_where_a_walls_top_holds_the_box_up() -> None:
    # 6 N up at 0.1 m along -x of the centre, 0.075 m below it: torque r x f.
    r, f = np.array([-0.1, 0.0, -0.075]), np.array([0.0, 0.0, 6.0])
    assert_allclose(bearing_point(f, np.cross(r, f)), [-0.1, 0.0], atol=1e-12)
    # A wall's face pushing sideways bears up on nothing.
    assert_allclose(bearing_point([5.0, 0.0, 0.0], [0.0, 0.4, 0.0]), [0.0, 0.0])


def test_the_search_slides_away_from_the_wall_top_once_the_descent_stops_on_it() -> None:
    r = np.array([0.0, -0.15, -0.075])
    for up, speed in ((0.0, 0.0), (2.0, 0.005), (10.0, 0.005)):
        f = np.array([0.0, 0.0, up])
        v = search_velocity(f, np.cross(r, f), GAINS)
        assert_allclose(v, [0.0, speed], atol=1e-12)  # towards +y: the slot's side
    # The descent stops at 2 N up (a wall's top) but only at 15 N sideways (a wall's face).
    assert float(descent_rate(felt_force([0.0, 0.0, 2.0], GAINS), GAINS)) == 0.0
    assert float(descent_rate(felt_force([10.0, 0.0, 0.0], GAINS), GAINS)) == pytest.approx(0.5)
    # The targets never shift farther than max_shift.
    f = np.array([0.0, 0.0, 3.0])
    offset, rate = admittance_step([0.0, 0.0199], f, [0.0, 0.0], GAINS, 1.0, np.cross(r, f))
    assert rate == 0.0
    assert np.linalg.norm(offset) == pytest.approx(0.02)


def test_the_truth_moves_a_fixture_with_its_offset_and_the_table() -> None:
    spec = world_spec(load_world(SLOT)).scene
    truth = PhysicalTruth(table_dz_m=0.01, fixtures=(FixtureTruth("slot", (0.007, -0.002)),))
    moved = physical_scene(spec, truth).fixtures[0]
    assert_allclose(np.subtract(moved.position, spec.fixtures[0].position), [0.007, -0.002, 0.01])
    with pytest.raises(ValueError, match="fixture names"):
        physical_scene(spec, PhysicalTruth(fixtures=(FixtureTruth("nowhere"),)))


def test_hard_draws_each_fixtures_offset_within_its_range() -> None:
    world = load_world(SLOT)
    low, high = world.trials.hard.fixture_offset_m
    offsets = [draw_hard(world, 0, i).truth.fixtures[0].offset_m for i in range(200)]
    distances = np.linalg.norm(offsets, axis=1)
    assert np.all((distances >= low) & (distances <= high + 1e-12))
    assert draw_hard(world, 0, 3).truth == draw_hard(world, 0, 3).truth
    headings = np.arctan2(*np.array(offsets).T[::-1])
    assert np.ptp(headings) > math.pi  # all round the table, not one side


def test_a_bad_fixture_offset_range_is_refused_naming_the_field() -> None:
    data = load_world(SLOT).model_dump(mode="json")
    data["trials"]["hard"] = {"fixture_offset_m": [0.0, 0.5]}
    with pytest.raises(ValueError, match=r"fixture_offset_m[\s\S]*within \[0, 0.1\] m"):
        world_from_data(data, SLOT)


def test_the_reasoner_plans_an_insertion_for_a_goal_in_a_fixture_only() -> None:
    from affordances import reason
    from worlds.adapters import object_contexts, robot_capabilities

    world = load_world(SLOT)
    context = object_contexts(world)[0]
    best = reason(context, robot_capabilities(world))[0]
    assert best.skill(Action.INSERT) is not None
    assert any("fixture 'slot'" in b for b in best.because)
    plain = dataclasses.replace(context, goal_fixtures=("",))
    assert reason(plain, robot_capabilities(world))[0].skill(Action.INSERT) is None
    assert AffordanceElement.IN_FIXTURE.value == "in_fixture"


def _episode(coupled: bool) -> tuple[object, int]:
    """One episode with the slot 7 mm off along +x; the report and the insertions timed out."""
    from experiment.episode import load_library, run_episode
    from skills.library import SkillLibrary

    world = load_world(SLOT)
    library = load_library(world)
    if not coupled:  # the same descent, no admittance: no yielding, centring or search
        off = {"compliance": 0.0, "centring": 0.0, "search_speed": 0.0}
        library = SkillLibrary(
            [
                dataclasses.replace(s, params={**s.params, **off})
                if s.action is Action.INSERT
                else s
                for s in library
            ]
        )
    timeouts = []

    def watch(_t: float, leaf: str, feedback: str) -> None:
        if leaf.endswith("insert_guard") and "timed out" in feedback:
            timeouts.append(feedback)

    truth = PhysicalTruth(fixtures=(FixtureTruth("slot", (0.007, 0.0)),))
    report = run_episode(
        world, library=library, out=None, animation=False, truth=truth, progress=watch
    )
    return report, len(timeouts)


@pytest.mark.sim
def test_the_coupling_seats_the_box_in_a_fixture_off_its_file_place() -> None:
    report, timeouts = _episode(coupled=True)
    assert report.success, report.failure  # type: ignore[attr-defined]
    assert timeouts == 0  # seated by the first insertion, not by the tree's retry
    seat = report.insertion["slot"]  # type: ignore[attr-defined]
    assert abs(seat["seat_bottom_m"]) <= SEATED_TOLERANCE_M
    assert seat["seat_angle_deg"] <= SEATED_TOLERANCE_DEG
    assert seat["peak_wall_force_n"] > 5.0  # the box did meet a wall
    assert seat["longest_above_limit_s"] <= WALL_FORCE_LIMIT_S

    bare, bare_timeouts = _episode(coupled=False)
    bare_seat = bare.insertion["slot"]  # type: ignore[attr-defined]
    # Without the coupling the box stays on the wall's top: not seated, every insertion
    # timed out (or, had it got in, it pressed the wall harder).
    assert not bare.success or bare_seat["peak_wall_force_n"] > seat["peak_wall_force_n"]  # type: ignore[attr-defined]
    assert bare_timeouts >= 1
    assert abs(bare_seat["seat_bottom_m"]) > SEATED_TOLERANCE_M
