"""Every robot leaf ticked alone against the in-memory world."""

from __future__ import annotations

import dataclasses
import re
from pathlib import Path
from typing import Any

import numpy as np
import py_trees
import pytest
from py_trees.common import Status

from affordances import SemanticAction, SkillSelection
from planner.composition import MovePlan, compose_move, squeeze_force
from planner.grips import lateral_geometry
from planner.leaves import (
    Approach,
    AtGoal,
    IsHeld,
    PathClear,
    Release,
    Retreat,
    SelectSkills,
    Transport,
)
from planner.leaves.base import SQUEEZE_FORCE_N
from planner.leaves.release import MAX_REOPENINGS
from planner.move_result import MoveResult, move_placements, move_results, publish_move_result
from planner.port import Pose
from planner.testing import (
    CONTROL_DT,
    FakeWorld,
    grasp_object,
    select_skills,
    set_up,
    set_up_carry,
    tick_until,
)
from planner.testing.fake_world import FakeObject
from planner.testing.fixtures import paper_moves
from planner.testing.harness import TickLog
from planner.wiring import wire
from skills import quaternion as quat
from skills.composer import DualArmState
from skills.library import SkillLibrary
from skills.vocabulary import ARMS, Action, Arm, GraspType, Space


def blackboard_value(key: str) -> object:
    return py_trees.blackboard.Blackboard.get(key)


def select_weighted(world: FakeWorld, library: SkillLibrary, weights: str) -> TickLog:
    """SelectSkills ticked with its ``weights`` port set."""
    leaf = set_up(
        SelectSkills("select"), world, library, object="parcel", plan="{plan}", weights=weights
    )
    return tick_until(leaf, world, CONTROL_DT)


def test_select_skills_chooses_the_papers_lateral_grasp(
    fake_world: FakeWorld, library: SkillLibrary
) -> None:
    plan = select_skills(fake_world, library)
    assert plan.grasp is GraspType.TWO_PALM_LATERAL
    assert {Action.TRANSPORT, Action.HOLD_LATERAL} <= set(plan.actions)


def test_select_skills_weights_replace_the_reasoners_and_keep_the_rest(
    fake_world: FakeWorld, library: SkillLibrary
) -> None:
    reasoned = select_skills(fake_world, library)
    log = select_weighted(fake_world, library, "hold_lateral=0; avoid_links = 0.5")
    assert log.final == Status.SUCCESS, log.feedback
    plan = blackboard_value("/plan")
    assert isinstance(plan, SemanticAction)
    weights = {s.action: s.weight for s in plan.skills}
    assert weights[Action.HOLD_LATERAL] == 0.0
    assert weights[Action.AVOID_LINKS] == 0.5
    for sel in reasoned.skills:
        if sel.action not in (Action.HOLD_LATERAL, Action.AVOID_LINKS):
            assert weights[sel.action] == sel.weight
    held, reasoned_held = plan.skill(Action.HOLD_LATERAL), reasoned.skill(Action.HOLD_LATERAL)
    assert held is not None and reasoned_held is not None
    assert held.params == reasoned_held.params


@pytest.mark.parametrize(
    ("weights", "expected"),
    [
        ("hold=0", "'hold=0': expected ACTION=NUMBER with ACTION one of approach"),
        ("hold_lateral", "'hold_lateral': expected a finite number after '='"),
        ("hold_lateral=nan", "'hold_lateral=nan': expected a finite number"),
        ("insert=1", "weights: insert not in the plan for parcel"),
    ],
)
def test_select_skills_refuses_weights_it_cannot_apply(
    fake_world: FakeWorld, library: SkillLibrary, weights: str, expected: str
) -> None:
    log = select_weighted(fake_world, library, weights)
    assert log.final == Status.FAILURE
    assert expected in log.feedback


def test_select_skills_fails_with_an_explanation_without_a_world(library: SkillLibrary) -> None:
    leaf = SelectSkills("select")
    wire(leaf, object="parcel", plan="{plan}")
    leaf.tick_once()
    assert leaf.status == Status.FAILURE
    assert "expected setup(world=...)" in leaf.feedback_message


def test_approach_ends_beside_the_faces(fake_world: FakeWorld, library: SkillLibrary) -> None:
    log = tick_until(
        set_up(Approach("approach"), fake_world, library, object="parcel", standoff_m=0.04),
        fake_world,
        CONTROL_DT,
    )
    assert log.final == Status.SUCCESS
    assert log.statuses[:-1] == (Status.RUNNING,) * (len(log.statuses) - 1)
    g = lateral_geometry(fake_world, "parcel")
    obj = fake_world.object_pose("parcel")
    for arm in ARMS:
        expect = obj.position + g.position(arm) - 0.04 * g.normal(arm)
        assert np.linalg.norm(fake_world.palm_pose(arm).position - expect) < 3e-3
    # It went through the set-point above: the palms rose above their end height.
    heights = [c.pose.position[2] for c in fake_world.commands]
    assert max(heights) > obj.position[2] + 0.05


def test_grasp_squeezes_to_the_force_and_hands_over_a_state(
    fake_world: FakeWorld, library: SkillLibrary
) -> None:
    grasp_object(fake_world, library)
    forces = [fake_world.contact_force(arm, "parcel") for arm in ARMS]
    assert min(forces) >= 0.8 * SQUEEZE_FORCE_N
    state = blackboard_value("/state")
    assert np.allclose(state.object.position, fake_world.object_pose("parcel").position, atol=1e-3)


def test_transport_reaches_each_goal_and_hands_over(
    fake_world: FakeWorld, library: SkillLibrary
) -> None:
    grasp_object(fake_world, library)
    for move in range(3):
        leaf = set_up(
            Transport(f"move{move}"),
            fake_world,
            library,
            object="parcel",
            move=move,
            plan="{plan}",
            from_state="{state}",
            to_state="{state}",
        )
        log = tick_until(leaf, fake_world, CONTROL_DT, max_ticks=3000)
        assert log.final == Status.SUCCESS, log.feedback
        at_goal = set_up(
            AtGoal("at_goal"),
            fake_world,
            library,
            object="parcel",
            move=move,
            tolerance_m=0.01,
            tolerance_deg=2.0,
        )
        at_goal.tick_once()
        assert at_goal.status == Status.SUCCESS, at_goal.feedback_message


def test_transport_publishes_its_moves_composition_and_placement(
    fake_world: FakeWorld, library: SkillLibrary
) -> None:
    grasp_object(fake_world, library)
    leaf = set_up_carry(
        fake_world,
        library,
        move=1,
        leaf_name="move1",
        transport_weight=0.25,
        avoid_gain=0.0,
    )
    assert move_results() == {}
    leaf.tick_once()
    running = move_results()[("parcel", 1)]
    assert running == MoveResult("parcel", 1, 0.25, 0.0, Status.RUNNING, skill="pick_and_place")
    log = tick_until(leaf, fake_world, CONTROL_DT, max_ticks=3000)
    assert log.final == Status.SUCCESS, log.feedback
    done = move_results()[("parcel", 1)]
    assert (done.status, done.transport_weight, done.avoid_gain) == (Status.SUCCESS, 0.25, 0.0)
    goal = fake_world.task_moves("parcel")[1].goal
    pose = fake_world.object_pose("parcel")
    assert done.placement_error_m == pytest.approx(np.linalg.norm(pose.position - goal.position))
    assert done.placement_error_rad == pytest.approx(
        quat.angle_between(pose.orientation, goal.orientation)
    )
    assert running.status == Status.RUNNING  # a published result is never changed after
    leaf.stop(Status.INVALID)  # a parent resetting the finished leaf is not a new result
    assert move_results()[("parcel", 1)] == done


class SaggingWorld(FakeWorld):
    """A held object measured ``sag_m`` below where the palms carry it (as a real grip lets a
    heavy box slide down), once ``sag_m`` is set."""

    sag_m = 0.0

    def object_pose(self, name: str) -> Pose:
        pose = super().object_pose(name)
        if min(self.contact_force(arm, name) for arm in ARMS) > 0.0:
            return Pose(pose.position - np.array([0.0, 0.0, self.sag_m]), pose.orientation)
        return pose


def sagging_world() -> SaggingWorld:
    return SaggingWorld(
        objects=[FakeObject("parcel", np.array([0.20, 0.30, 0.15]))], moves=paper_moves()
    )


def carry_sagging(library: SkillLibrary, sag_m: float) -> tuple[Status, str, SaggingWorld]:
    world = sagging_world()
    grasp_object(world, library)
    leaf = set_up_carry(
        world,
        library,
        leaf_name="move0",
    )
    # The object starts to hang below the palms once the move is composed (from where it
    # was measured): the commanded path no longer says where the object is.
    leaf.tick_once()
    world.sag_m = sag_m
    log = tick_until(leaf, world, CONTROL_DT, max_ticks=3000)
    return log.final, leaf.feedback_message, world


def test_transport_judges_the_measured_object_not_its_commanded_path(
    library: SkillLibrary,
) -> None:
    # The commanded object arrives exactly, but the object hangs 45 mm below it: not placed.
    status, feedback, _ = carry_sagging(library, 0.045)
    assert status == Status.FAILURE
    # (the kinematic fake carries to within a millimetre of the commanded goal)
    assert re.fullmatch(
        r"came to rest 4[45]\.\d mm, 0\.0 deg from the goal \(tolerance 20 mm, 10 deg\)", feedback
    ), feedback
    done = move_results()[("parcel", 0)]
    assert done.status == Status.FAILURE and done.placement_error_m is None


def test_transport_reports_the_measured_placement_within_tolerance(
    library: SkillLibrary,
) -> None:
    status, feedback, world = carry_sagging(library, 0.011)
    assert status == Status.SUCCESS, feedback
    assert re.fullmatch(r"placed 1[01]\.\d mm, 0\.0 deg from the goal", feedback), feedback
    done = move_results()[("parcel", 0)]
    assert done.placement_error_m == pytest.approx(0.011, abs=1e-3)  # what it measures
    pose = world.object_pose("parcel")
    goal = world.task_moves("parcel")[0].goal
    assert done.placement_error_m == pytest.approx(np.linalg.norm(pose.position - goal.position))


def test_transport_lifts_the_parcel_on_the_way(
    fake_world: FakeWorld, library: SkillLibrary
) -> None:
    grasp_object(fake_world, library)
    leaf = set_up_carry(
        fake_world,
        library,
        leaf_name="move0",
    )
    heights = []
    for _ in range(600):
        leaf.tick_once()
        fake_world.advance(CONTROL_DT)
        heights.append(fake_world.object_pose("parcel").position[2])
        if leaf.status != Status.RUNNING:
            break
    assert max(heights) - 0.675 > 0.03


def test_transport_fails_when_the_grip_is_lost(
    fake_world: FakeWorld, library: SkillLibrary
) -> None:
    grasp_object(fake_world, library)
    leaf = set_up_carry(
        fake_world,
        library,
        leaf_name="move0",
    )
    for _ in range(30):
        leaf.tick_once()
        fake_world.advance(CONTROL_DT)
    fake_world.drop("parcel")
    log = tick_until(leaf, fake_world, CONTROL_DT)
    assert log.final == Status.FAILURE
    assert "grip lost" in log.feedback
    failed = move_results()[("parcel", 0)]
    assert failed.status == Status.FAILURE and failed.placement_error_m is None


def test_halting_a_running_transport_stops_the_arms(
    fake_world: FakeWorld, library: SkillLibrary
) -> None:
    grasp_object(fake_world, library)
    leaf = set_up_carry(
        fake_world,
        library,
        leaf_name="move0",
    )
    for _ in range(40):
        leaf.tick_once()
        fake_world.advance(CONTROL_DT)
    assert leaf.status == Status.RUNNING
    moving = fake_world.commands[-1].twist
    assert np.linalg.norm(moving) > 1e-3
    leaf.stop(Status.INVALID)  # what a parent's preemption does
    assert fake_world.holds == 1
    assert move_results()[("parcel", 0)].status == Status.INVALID  # published as halted
    last_two = fake_world.commands[-2:]
    assert {c.arm for c in last_two} == set(ARMS)
    assert all(np.all(c.twist == 0.0) for c in last_two)


def test_is_held_reads_forces_and_fails_after_a_drop(
    fake_world: FakeWorld, library: SkillLibrary
) -> None:
    held = set_up(IsHeld("held"), fake_world, library, object="parcel")
    held.tick_once()
    assert held.status == Status.FAILURE and "not held" in held.feedback_message
    grasp_object(fake_world, library)
    fake_world.advance(CONTROL_DT)
    held.tick_once()
    assert held.status == Status.SUCCESS, held.feedback_message
    fake_world.drop("parcel")
    held.tick_once()
    assert held.status == Status.FAILURE


def test_is_held_with_the_grasps_state_fails_when_a_palm_slid_along_its_face(
    fake_world: FakeWorld, library: SkillLibrary
) -> None:
    grasp_object(fake_world, library)
    fake_world.advance(CONTROL_DT)
    held = set_up(IsHeld("held"), fake_world, library, object="parcel", from_state="{state}")
    held.tick_once()
    assert held.status == Status.SUCCESS, held.feedback_message
    palms = {arm: fake_world.palm_pose(arm) for arm in ARMS}
    # pressing 5 mm deeper into the faces is a squeeze, not a slip
    inward = {
        arm: Pose(
            p.position - (0.005 if arm is Arm.LEFT else -0.005) * np.array([0, 1.0, 0]),
            p.orientation,
        )
        for arm, p in palms.items()
    }
    fake_world.place_palms(inward)
    held.tick_once()
    assert held.status == Status.SUCCESS, held.feedback_message
    # the right palm 30 mm lower on its face: a turned grip shifts that much, still sound
    lower = {
        Arm.RIGHT: Pose(palms[Arm.RIGHT].position - [0.0, 0.0, 0.03], palms[Arm.RIGHT].orientation)
    }
    fake_world.place_palms(lower)
    held.tick_once()
    assert held.status == Status.SUCCESS, held.feedback_message
    # and 60 mm along its face to the front: the parcel slipped in the grip
    ahead = {
        Arm.RIGHT: Pose(palms[Arm.RIGHT].position + [0.06, 0.0, 0.0], palms[Arm.RIGHT].orientation)
    }
    fake_world.place_palms(ahead)
    held.tick_once()
    assert held.status == Status.FAILURE
    assert re.search(
        r"slipped in the grip: the right palm 6\d\.\d mm along its face", held.feedback_message
    )


def test_at_goal_reports_the_errors(fake_world: FakeWorld, library: SkillLibrary) -> None:
    leaf = set_up(AtGoal("at_goal"), fake_world, library, object="parcel", move=0)
    leaf.tick_once()
    assert leaf.status == Status.FAILURE
    assert "100.0 mm" in leaf.feedback_message
    bad = set_up(AtGoal("bad"), fake_world, library, object="parcel", move=7)
    bad.tick_once()
    assert "expected an index below 3" in bad.feedback_message


def test_at_goal_places_a_carry_it_finds_there_running_or_halted(
    fake_world: FakeWorld, library: SkillLibrary
) -> None:
    # ReactiveFallback(AtGoal, carry): AtGoal succeeds while the carry runs and the parent
    # halts it, so no Transport ever publishes the move's placement; the judge read none.
    goal = fake_world.task_moves("parcel")[0].goal
    fake_world.object_pose = lambda name: goal  # type: ignore[method-assign]
    leaf = set_up(AtGoal("at_goal"), fake_world, library, object="parcel", move=0)
    leaf.tick_once()
    assert leaf.status == Status.SUCCESS and move_placements() == {}  # no carry of it: nothing
    carrying = MoveResult("parcel", 0, 1.0, 0.0, Status.RUNNING, skill="pick_and_place")
    publish_move_result(carrying, "carry")
    leaf.tick_once()
    placed = move_placements()[("parcel", 0)]
    assert placed.status == Status.SUCCESS and placed.skill == "pick_and_place"
    assert placed.placement_error_m == pytest.approx(0.0, abs=1e-9)
    # A move placed before keeps its placement (a correction halted there changes nothing).
    publish_move_result(dataclasses.replace(carrying, status=Status.INVALID), "carry")
    leaf.tick_once()
    assert move_placements()[("parcel", 0)] is placed


def _plan_without_avoidance(plan: SemanticAction) -> SemanticAction:
    keep = tuple(s for s in plan.skills if s.action in (Action.TRANSPORT, Action.HOLD_LATERAL))
    return SemanticAction(plan.grasp, keep, plan.score, plan.because)


def test_path_clear_sees_an_obstacle_on_the_straight_path(
    fake_world: FakeWorld, library: SkillLibrary
) -> None:
    plan = grasp_object(fake_world, library)
    fake_world.advance(CONTROL_DT)
    bare = _plan_without_avoidance(plan)
    py_trees.blackboard.Blackboard.set("/bare", bare)
    clear = set_up(
        PathClear("clear0"),
        fake_world,
        library,
        object="parcel",
        move=0,
        plan="{bare}",
        from_state="{state}",
    )
    clear.tick_once()
    assert clear.status == Status.SUCCESS, clear.feedback_message
    blocked = set_up(
        PathClear("clear1"),
        fake_world,
        library,
        object="parcel",
        move=1,
        plan="{bare}",
        from_state="{state}",
    )
    blocked.tick_once()
    assert blocked.status == Status.FAILURE
    assert "predicted collision" in blocked.feedback_message


@pytest.mark.parametrize(("lag_m", "status"), [(0.05, Status.SUCCESS), (0.2, Status.FAILURE)])
def test_a_motion_arrives_only_where_the_palms_are(
    library: SkillLibrary, lag_m: float, status: Status
) -> None:
    # A palm that settles 5 cm off its target (a biased actuator) has arrived; one held 20 cm
    # short (an arm pinned) has not, and the leaf says which palm and how far.
    world = FakeWorld(objects=[FakeObject("parcel", np.array([0.20, 0.30, 0.15]))])
    world.bias_palm(Arm.LEFT, [0.0, lag_m, 0.0])
    leaf = set_up(Approach("approach"), world, library, object="parcel", standoff_m=0.04)
    log = tick_until(leaf, world, CONTROL_DT)
    assert log.final == status
    if status == Status.FAILURE:
        assert re.search(r"the left palm stopped 20\d mm from its pose", log.feedback)
        assert log.statuses[:-1] == (Status.RUNNING,) * (len(log.statuses) - 1)


def test_release_then_retreat(fake_world: FakeWorld, library: SkillLibrary) -> None:
    grasp_object(fake_world, library)
    log = tick_until(
        set_up(
            Release("release"),
            fake_world,
            library,
            object="parcel",
            from_state="{state}",
            to_state="{state}",
        ),
        fake_world,
        CONTROL_DT,
    )
    assert log.final == Status.SUCCESS, log.feedback
    assert max(fake_world.contact_force(a, "parcel") for a in ARMS) == 0.0
    log = tick_until(set_up(Retreat("retreat"), fake_world, library), fake_world, CONTROL_DT)
    assert log.final == Status.SUCCESS, log.feedback
    for arm in ARMS:
        rest = fake_world.rest_palm_pose(arm)
        assert np.linalg.norm(fake_world.palm_pose(arm).position - rest.position) < 3e-3


class LeaningWorld(FakeWorld):
    """An object that leans on the left palm with 2 N until that palm is ``lean_m`` out from
    where the release found it (a tipped box following the palm that held it)."""

    lean_m = 0.08
    found: np.ndarray | None = None

    def contact_force(self, arm: Arm, name: str) -> float:
        force = super().contact_force(arm, name)
        if arm is Arm.LEFT and self.found is not None:
            if np.linalg.norm(self.palm_pose(arm).position - self.found) < self.lean_m:
                return max(force, 2.0)
        return force


def _release_on_leaning(
    library: SkillLibrary, lean_m: float, max_ticks: int
) -> tuple[Status, Release, LeaningWorld]:
    """Grasp, then release in a world whose object leans on the left palm for ``lean_m``."""
    world = LeaningWorld(
        objects=[FakeObject("parcel", np.array([0.20, 0.30, 0.15]))], moves=paper_moves()
    )
    world.lean_m = lean_m
    grasp_object(world, library)
    world.found = world.palm_pose(Arm.LEFT).position.copy()
    leaf = set_up(
        Release("release"),
        world,
        library,
        object="parcel",
        from_state="{state}",
        to_state="{state}",
    )
    log = tick_until(leaf, world, CONTROL_DT, max_ticks=max_ticks)
    assert isinstance(leaf, Release)
    return log.final, leaf, world


def test_release_opens_further_when_the_object_leans_on_a_palm(library: SkillLibrary) -> None:
    final, leaf, world = _release_on_leaning(library, 0.08, 2000)
    assert final == Status.SUCCESS, leaf.feedback_message
    # One opening of 5 cm leaves the palm pressed; the release opened again and cleared it.
    assert leaf.reopenings == 1
    assert world.found is not None
    assert np.linalg.norm(world.palm_pose(Arm.LEFT).position - world.found) > world.lean_m
    # An object that never lets go ends the release's retries without a success.
    final, leaf, world = _release_on_leaning(library, 10.0, 1500)
    assert final == Status.RUNNING
    assert leaf.reopenings == MAX_REOPENINGS
    assert "2.0 N" in leaf.feedback_message


def test_selection_helpers_are_typed() -> None:
    sel = SkillSelection(Action.TRANSPORT, Space.ABSOLUTE, 1.0, {})
    assert sel.action is Action.TRANSPORT
    assert Pose.of([0, 0, 0], quat.IDENTITY).position.shape == (3,)


def test_transport_runs_the_composition_path_clear_checked(
    fake_world: FakeWorld, library: SkillLibrary, monkeypatch: pytest.MonkeyPatch
) -> None:
    plan = grasp_object(fake_world, library)
    py_trees.blackboard.Blackboard.set("/bare", _plan_without_avoidance(plan))
    activated: list[tuple[str, ...]] = []
    activate = fake_world.set_active_obstacles
    monkeypatch.setattr(
        fake_world,
        "set_active_obstacles",
        lambda names: (activated.append(tuple(names)), activate(names)),
    )
    ports = {"object": "parcel", "move": 0, "plan": "{bare}", "from_state": "{state}"}
    clear = set_up(PathClear("clear"), fake_world, library, composition="{checked}", **ports)
    clear.tick_once()
    assert clear.status == Status.SUCCESS, clear.feedback_message
    checked = blackboard_value("/checked")
    assert isinstance(checked, MovePlan) and checked.index == 0
    carry = set_up(
        Transport("carry"),
        fake_world,
        library,
        composition="{checked}",
        to_state="{state}",
        **ports,
    )
    log = tick_until(carry, fake_world, CONTROL_DT, max_ticks=3000)
    assert log.final == Status.SUCCESS, log.feedback
    # Composed once: Transport ran the checked terms, and only PathClear switched obstacles on.
    assert carry.composer is not None and carry.composer.absolute is checked.composer.absolute
    assert activated == [()]


def test_transport_refuses_a_composition_checked_for_another_variant(
    fake_world: FakeWorld, library: SkillLibrary
) -> None:
    plan = grasp_object(fake_world, library)
    py_trees.blackboard.Blackboard.set("/bare", _plan_without_avoidance(plan))
    ports = {"object": "parcel", "move": 0, "plan": "{bare}", "from_state": "{state}"}
    clear = set_up(PathClear("clear"), fake_world, library, composition="{checked}", **ports)
    clear.tick_once()
    assert clear.status == Status.SUCCESS, clear.feedback_message
    carry = set_up(
        Transport("carry"),
        fake_world,
        library,
        composition="{checked}",
        avoid_gain=2.0,
        to_state="{state}",
        **ports,
    )
    carry.tick_once()
    assert carry.status == Status.FAILURE
    assert "not the composition of this move: avoid_gain 2.0, checked with 1.0" in (
        carry.feedback_message
    )


def test_a_carry_without_grasp_maintenance_leaves_a_knocked_palm_reference_coasting(
    fake_world: FakeWorld, library: SkillLibrary
) -> None:
    """hold_gain 0 composes the hold terms at weight 0 (and PathClear's check must be of the
    same gain): a palm's reference knocked into motion in {O} coasts on without them and is
    held near the grasp with them."""
    plan = grasp_object(fake_world, library)
    py_trees.blackboard.Blackboard.set("/bare", _plan_without_avoidance(plan))
    ports = {"object": "parcel", "move": 0, "plan": "{bare}", "from_state": "{state}"}
    clear = set_up(
        PathClear("clear"), fake_world, library, composition="{checked}", hold_gain=0.0, **ports
    )
    clear.tick_once()
    assert clear.status == Status.SUCCESS, clear.feedback_message
    checked = blackboard_value("/checked")
    assert isinstance(checked, MovePlan) and checked.hold_gain == 0.0
    assert all(w.weight == 0.0 for arm in ARMS for w in checked.composer.relative[arm])
    carry = set_up(Transport("carry"), fake_world, library, composition="{checked}", **ports)
    carry.tick_once()
    assert carry.status == Status.FAILURE
    assert "hold_gain 1.0, checked with 0.0" in carry.feedback_message
    state = blackboard_value("/state")
    assert isinstance(state, DualArmState)
    # The left palm's reference moving off the grasp at 2 cm/s (a knock), nothing else moving.
    left = state.left._replace(
        velocity=np.array([0.0, 0.0, 0.02]),
        acceleration=np.zeros(3),
        angular_velocity=np.zeros(3),
        angular_acceleration=np.zeros(3),
    )
    shifted = dataclasses.replace(state, left=left)
    drift = {}
    for gain in (0.0, 1.0):
        move = compose_move(
            _plan_without_avoidance(plan),
            library,
            fake_world,
            "parcel",
            0,
            shifted,
            25.0,
            hold_gain=gain,
        )
        composer = move.fresh()
        for _ in range(30):
            composer.step(CONTROL_DT)
        start = move.start.relative(Arm.LEFT).position
        drift[gain] = float(np.linalg.norm(composer.state.relative(Arm.LEFT).position - start))
    # Unheld, the reference coasts on (0.5 s at 2 cm/s); held, the spring-damper stops it.
    assert drift[0.0] == pytest.approx(0.01, rel=0.05)
    assert drift[1.0] < 0.5 * drift[0.0]


def test_squeeze_force_is_the_plans_or_the_default_never_above_the_robots_rating() -> None:
    assert squeeze_force(None, 25.0) == 25.0
    # a robot rated below the default squeezes at its rating (the iCub's 20 N)
    assert squeeze_force(None, 25.0, rated=20.0) == 20.0

    class _Plan:  # the one thing squeeze_force reads of a SemanticAction
        def __init__(self, need: float) -> None:
            self.need = need

        def skill(self, action: Action) -> SkillSelection | None:
            assert action is Action.HOLD_LATERAL
            return SkillSelection(
                Action.HOLD_LATERAL, Space.RELATIVE, 1.0, {"squeeze_force_n": self.need}
            )

    # the plan's own need wins over the default, still capped by the rating
    assert squeeze_force(_Plan(32.0), 25.0, rated=40.0) == 32.0  # type: ignore[arg-type]
    assert squeeze_force(_Plan(10.0), 25.0, rated=40.0) == 25.0  # type: ignore[arg-type]
    assert squeeze_force(_Plan(32.0), 25.0, rated=30.0) == 30.0  # type: ignore[arg-type]


def test_a_tree_with_weights_that_cannot_apply_is_refused_when_read(tmp_path: Path) -> None:
    from planner.loader import TreeFileError, load_tree
    from planner.tree_dataflow import RUN_WRITES

    shipped = Path(__file__).resolve().parents[2] / "planner" / "trees" / "pick_and_place.xml"
    text = shipped.read_text(encoding="utf-8").replace(
        'plan="{plan}"/>', 'plan="{plan}" weights="avoid_links=0.5; hold=0"/>', 1
    )
    assert 'weights="avoid_links' in text
    bad = tmp_path / "bad_weights.xml"
    bad.write_text(text, encoding="utf-8")
    with pytest.raises(TreeFileError) as err:
        load_tree(bad, run_keys=RUN_WRITES)
    message = str(err.value)
    assert "bad_weights.xml:" in message and "port 'weights'" in message
    assert "'hold=0': expected ACTION=NUMBER" in message


@pytest.mark.parametrize("port, expected", [(None, True), ("false", False), ("true", True)])
def test_path_clear_asks_the_world_for_link_doubt_as_its_port_says(
    fake_world: FakeWorld,
    library: SkillLibrary,
    monkeypatch: pytest.MonkeyPatch,
    port: str | None,
    expected: bool,
) -> None:
    plan = grasp_object(fake_world, library)
    py_trees.blackboard.Blackboard.set("/bare", _plan_without_avoidance(plan))
    asked: list[bool] = []
    check = fake_world.check_trajectory

    def recording(*args: Any, link_doubt: bool = True, **kwargs: Any) -> Any:
        asked.append(link_doubt)
        return check(*args, link_doubt=link_doubt, **kwargs)

    monkeypatch.setattr(fake_world, "check_trajectory", recording)
    ports: dict[str, Any] = {
        "object": "parcel",
        "move": 0,
        "plan": "{bare}",
        "from_state": "{state}",
    }
    if port is not None:
        ports["link_doubt"] = port
    clear = set_up(PathClear("clear"), fake_world, library, composition="{checked}", **ports)
    clear.tick_once()
    assert clear.status == Status.SUCCESS, clear.feedback_message
    assert asked == [expected]
