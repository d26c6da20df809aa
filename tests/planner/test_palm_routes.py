"""Approach and Retreat predict their palms' path and take another way round a sphere in it."""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np
from numpy.testing import assert_allclose
from py_trees.common import Status

from planner.leaves import Approach, Retreat
from planner.leaves.approach import RISE_FIRST_M, rising_first
from planner.leaves.palm_motion import measured_state
from planner.leaves.palm_routes import PalmRoute, choose_route, predict_palm_path
from planner.port import ObstacleInfo, PathCheck, Pose
from planner.testing import FakeWorld
from planner.testing.fake_world import FakeObject
from planner.testing.harness import TickLog
from skills import quaternion as quat
from skills.vocabulary import ARMS, Arm

Tick = Callable[..., TickLog]
DT = 1.0 / 60.0
BOX = np.array([0.20, 0.30, 0.15])


def commanded_path(world: FakeWorld) -> np.ndarray:
    """Palm positions as commanded, (N, 2, 3), left then right."""
    per_arm = [np.array([c.pose.position for c in world.commands if c.arm is a]) for a in ARMS]
    return np.stack(per_arm, axis=1)


def palms_beside_box(obstacles: list[ObstacleInfo]) -> FakeWorld:
    """The palms open 4 cm beside the box's faces (as after a release)."""
    world = FakeWorld(objects=[FakeObject("parcel", BOX)], obstacles=obstacles)
    for arm, side in ((Arm.LEFT, 1.0), (Arm.RIGHT, -1.0)):
        rest = world.rest_palm_pose(arm)
        world.command_palm(arm, Pose.of([0.55, side * 0.21, 0.675], rest.orientation))
    world.advance(DT)
    world.commands.clear()
    return world


def default_retreat(world: FakeWorld, back: float, rise: float) -> dict[Arm, list[Pose]]:
    out = {}
    for arm in ARMS:
        here = world.palm_pose(arm)
        away = here.position - back * quat.rotate(here.orientation, np.array([0.0, 0.0, 1.0]))
        out[arm] = [
            Pose(away, here.orientation),
            Pose(away + np.array([0.0, 0.0, rise]), here.orientation),
            world.rest_palm_pose(arm),
        ]
    return out


def test_retreat_with_nothing_near_takes_the_usual_way_exactly(tick_leaf: Tick) -> None:
    world = palms_beside_box([ObstacleInfo("far", np.array([1.5, 0.0, 0.8]), 0.04)])
    world.set_active_obstacles(["far"])
    starts = {a: measured_state(world.palm_pose(a), world.palm_twist(a)) for a in ARMS}
    usual = predict_palm_path(starts, default_retreat(world, 0.04, 0.1), 1.0, DT)
    log = tick_leaf(Retreat("retreat"), world, back_m=0.04, segment_s=1.0)
    assert log.final == Status.SUCCESS, log.feedback
    assert log.feedback == "palms at rest"
    path = commanded_path(world)
    assert_allclose(path, usual.positions[1 : len(path) + 1], rtol=0.0, atol=0.0)


def test_retreat_goes_round_a_sphere_on_its_usual_path(tick_leaf: Tick) -> None:
    world = palms_beside_box([])
    usual = default_retreat(world, 0.04, 0.1)
    # A sphere where the right palm would rise to.
    sphere = ObstacleInfo("ball", usual[Arm.RIGHT][1].position.copy(), 0.03)
    world = palms_beside_box([sphere])
    world.set_active_obstacles(["ball"])
    starts = {a: measured_state(world.palm_pose(a), world.palm_twist(a)) for a in ARMS}
    predicted = predict_palm_path(starts, usual, 1.0, DT)
    assert not world.check_palm_path(predicted.positions, predicted.orientations, 0.01).clear
    log = tick_leaf(Retreat("retreat"), world, back_m=0.04, segment_s=1.0)
    assert log.final == Status.SUCCESS, log.feedback
    assert "refused backing away and rising" in log.feedback
    path = commanded_path(world)
    check = world.check_palm_path(path, np.zeros((len(path), 2, 4)), 0.01)
    assert check.clear, check.detail


def test_approach_with_nothing_near_takes_the_usual_way(tick_leaf: Tick) -> None:
    world = FakeWorld(objects=[FakeObject("parcel", BOX)])
    log = tick_leaf(Approach("approach"), world, object="parcel")
    assert log.final == Status.SUCCESS, log.feedback
    assert log.feedback == "palms at the pre-grasp poses"


def test_approach_goes_round_a_sphere_on_its_usual_path(tick_leaf: Tick) -> None:
    plain = FakeWorld(objects=[FakeObject("parcel", BOX)])
    assert tick_leaf(Approach("approach"), plain, object="parcel").final == Status.SUCCESS
    usual = commanded_path(plain)
    # A small sphere a little below the right palm's usual way in, a fifth of the way along:
    # coming in from above passes over it.
    sphere = ObstacleInfo("ball", usual[len(usual) // 5, 1] - np.array([0.0, 0.0, 0.04]), 0.02)
    world = FakeWorld(objects=[FakeObject("parcel", BOX)], obstacles=[sphere])
    world.set_active_obstacles(["ball"])
    assert not world.check_palm_path(usual, np.zeros((len(usual), 2, 4)), 0.01).clear
    log = tick_leaf(Approach("approach"), world, object="parcel")
    assert log.final == Status.SUCCESS, log.feedback
    assert log.feedback.startswith("palms at the pre-grasp poses (by coming in from above")
    path = commanded_path(world)
    check = world.check_palm_path(path, np.zeros((len(path), 2, 4)), 0.01)
    assert check.clear, check.detail
    # Either way, the palms end beside the faces.
    assert_allclose(path[-1], usual[-1], atol=3e-3)


def test_a_leaf_boxed_in_keeps_the_usual_way_and_says_so(tick_leaf: Tick) -> None:
    world = palms_beside_box([])
    usual = default_retreat(world, 0.04, 0.1)
    # A sphere swallowing the right palm where it stands: every way starts in contact.
    sphere = ObstacleInfo("ball", world.palm_pose(Arm.RIGHT).position.copy(), 0.08)
    world = palms_beside_box([sphere])
    world.set_active_obstacles(["ball"])
    starts = {a: measured_state(world.palm_pose(a), world.palm_twist(a)) for a in ARMS}
    expected = predict_palm_path(starts, usual, 1.0, DT)
    log = tick_leaf(Retreat("retreat"), world, back_m=0.04, segment_s=1.0)
    assert log.final == Status.SUCCESS
    assert "no way predicted clear, by backing away and rising" in log.feedback
    path = commanded_path(world)
    assert_allclose(path, expected.positions[1 : len(path) + 1], rtol=0.0, atol=0.0)


def test_an_approach_whose_every_way_ends_in_an_obstacle_refuses_to_move(
    tick_leaf: Tick,
) -> None:
    plain = FakeWorld(objects=[FakeObject("parcel", BOX)])
    assert tick_leaf(Approach("approach"), plain, object="parcel").final == Status.SUCCESS
    end = commanded_path(plain)[-1, 1]
    # A sphere where the right palm's way in ends: every route to the faces ends in it.
    sphere = ObstacleInfo("ball", end + np.array([0.0, 0.0, 0.03]), 0.03)
    world = FakeWorld(objects=[FakeObject("parcel", BOX)], obstacles=[sphere])
    world.set_active_obstacles(["ball"])
    log = tick_leaf(Approach("approach"), world, object="parcel")
    assert log.final == Status.FAILURE
    assert log.feedback.startswith(
        "no way clear of contact: every way ends with a palm or an arm link on an obstacle"
    )
    assert "refused coming in from" in log.feedback
    assert not world.commands  # the palms stay where they are


def test_with_no_way_clear_of_contact_the_choice_says_when_every_way_ends_touching() -> None:
    world = palms_beside_box([])
    routes, starts = _two_routes(world)
    ends = [r.waypoints[Arm.LEFT][-1].position for r in routes]
    doubted = choose_route(_Refusing([]), starts, routes, 1.0, DT, 0.01, detour_of=None)
    assert not doubted.contact_free and doubted.ends_in_contact == ""
    # Only the usual way ending touching: another way ends elsewhere, so it is no refusal.
    one = choose_route(_Refusing([], touching_ends=[ends[0]]), starts, routes, 1.0, DT, 0.01, None)
    assert one.ends_in_contact == ""
    touching = _Refusing([], touching_ends=ends)
    chosen = choose_route(touching, starts, routes, 1.0, DT, 0.01, detour_of=None)
    assert chosen.route.name == "usual" and "on an obstacle" in chosen.ends_in_contact
    # Ending with a link on another object, one of those it goes around, is refused too;
    # on the object it goes to, or on one not among the others, it is not.
    box = ObstacleInfo("box", np.zeros(3), 0.1)
    on_box = _Refusing([], on_objects={"box"})
    chosen = choose_route(on_box, starts, routes, 1.0, DT, 0.01, detour_of=None, around=[box])
    assert chosen.ends_in_contact == "every way ends with an arm link on box"
    assert choose_route(on_box, starts, routes, 1.0, DT, 0.01, None).ends_in_contact == ""


def test_approach_refuses_an_object_fallen_off_the_table_saying_where(tick_leaf: Tick) -> None:
    fallen = FakeObject("parcel", BOX, pose=Pose.of([0.9, -0.3, 0.05]))
    log = tick_leaf(Approach("approach"), FakeWorld(objects=[fallen]), object="parcel")
    assert log.final == Status.FAILURE
    assert "parcel lies off the table, out of reach: at (0.90, -0.30, 0.05) m" in log.feedback
    assert "below the table top" in log.feedback
    beyond = FakeObject("parcel", BOX, pose=Pose.of([1.2, 0.0, 0.675]))
    log = tick_leaf(Approach("approach"), FakeWorld(objects=[beyond]), object="parcel")
    assert log.final == Status.FAILURE
    assert "beyond the table's edge" in log.feedback


class _Refusing:
    """A scene that refuses every route: those ending at ``sure_ends`` for a sure contact (a
    palm, or a link on a resting object), the others only within the forearms' doubt; a route
    ending at ``clear_end`` is clear; one ending at ``touching_ends`` ends touching; every one
    ends with a link on the objects named in ``on_objects``."""

    def __init__(
        self,
        sure_ends: list[np.ndarray],
        clear_end: np.ndarray | None = None,
        touching_ends: Sequence[np.ndarray] = (),
        on_objects: set[str] | None = None,
    ) -> None:
        self.sure_ends = sure_ends
        self.clear_end = clear_end
        self.touching_ends = list(touching_ends)
        self.on_objects = tuple(sorted(on_objects or ()))

    def obstacles(self) -> tuple[ObstacleInfo, ...]:
        return ()

    def check_palm_path(
        self,
        positions: np.ndarray,
        orientations: np.ndarray,
        margin_m: float,
        object_margin_m: float | None = None,
    ):
        end = positions[-1, 0]
        if self.clear_end is not None and np.allclose(end, self.clear_end, atol=1e-3):
            return PathCheck(True, 0.1)
        sure = any(np.allclose(end, e, atol=1e-3) for e in self.sure_ends)
        touches = any(np.allclose(end, e, atol=1e-3) for e in self.touching_ends)
        return PathCheck(
            False,
            0.1,
            3,
            "refused",
            doubtful=not sure,
            end_clear=not touches,
            end_objects=self.on_objects,
        )


def _two_routes(world: FakeWorld) -> tuple[list[PalmRoute], dict[Arm, object]]:
    starts = {a: measured_state(world.palm_pose(a), world.palm_twist(a)) for a in ARMS}
    routes = []
    for name, dz in (("usual", 0.10), ("other", 0.20)):
        routes.append(
            PalmRoute(
                name,
                {
                    a: [
                        Pose(
                            world.palm_pose(a).position + [0.0, 0.0, dz],
                            world.palm_pose(a).orientation,
                        )
                    ]
                    for a in ARMS
                },
            )
        )
    return routes, starts


def test_with_no_way_clear_a_route_only_doubted_beats_a_usual_one_sure_to_touch() -> None:
    world = palms_beside_box([])
    routes, starts = _two_routes(world)
    ends = [r.waypoints[Arm.LEFT][-1].position for r in routes]
    # The usual way sweeps a palm through a resting object; the other is doubted only.
    chosen = choose_route(_Refusing([ends[0]]), starts, routes, 1.0, DT, 0.01, detour_of=None)
    assert chosen.route.name == "other" and not chosen.clear and not chosen.contact_free
    # Both only doubted, or both sure to touch: the usual way, as before.
    for sure in ([], ends):
        chosen = choose_route(_Refusing(sure), starts, routes, 1.0, DT, 0.01, detour_of=None)
        assert chosen.route.name == "usual"


class _ObjectInTheWay:
    """A scene with no obstacle where a palm passing within ``radius`` of ``centre`` (another
    object, resting there) is sure to touch it."""

    def __init__(self, centre: np.ndarray, radius: float) -> None:
        self.centre, self.radius = centre, radius

    def obstacles(self) -> tuple[ObstacleInfo, ...]:
        return ()

    def near(self, positions: np.ndarray) -> np.ndarray:
        """(N,) whether a palm at each step (N, 2, 3) touches the object."""
        return np.linalg.norm(positions - self.centre, axis=-1).min(axis=-1) < self.radius

    def check_palm_path(
        self,
        positions: np.ndarray,
        orientations: np.ndarray,
        margin_m: float,
        object_margin_m: float | None = None,
    ) -> PathCheck:
        near = self.near(positions)
        if not near.any():
            return PathCheck(True, 0.1)
        return PathCheck(False, 0.1, int(np.argmax(near)), "on an object")


def test_a_way_in_goes_round_another_object_in_its_way() -> None:
    world = palms_beside_box([])
    starts = {a: measured_state(world.palm_pose(a), world.palm_twist(a)) for a in ARMS}
    ahead = {
        a: [Pose(world.palm_pose(a).position + [0.3, 0.0, 0.0], world.palm_pose(a).orientation)]
        for a in ARMS
    }
    routes = [PalmRoute("usual", ahead)]
    usual = predict_palm_path(starts, ahead, 1.0, DT)
    # Another object on the left palm's way, halfway along, a centimetre aside: without it
    # among those to go around (``around``), no detour is tried, as there is no obstacle.
    left = usual.positions[:, 0]
    halfway = left[np.argmin(np.abs(left[:, 0] - left[0, 0] - 0.15))]
    box = ObstacleInfo("box", halfway + [0.0, -0.01, 0.0], 0.05)
    scene = _ObjectInTheWay(box.position, box.radius)
    plain = choose_route(scene, starts, routes, 1.0, DT, 0.01, detour_of=0)
    assert plain.route.name == "usual" and not plain.clear
    detoured = choose_route(scene, starts, routes, 1.0, DT, 0.01, detour_of=0, around=[box])
    assert detoured.route.name == "usual, around the nearest obstacle", detoured.note
    assert detoured.clear


class _BoxScene(_ObjectInTheWay):
    """A scene whose only thing is a box resting at ``centre`` with half extents ``half``: a
    palm path entering it is refused."""

    def __init__(self, centre: np.ndarray, half: np.ndarray) -> None:
        self.centre, self.half = centre, half

    def near(self, positions: np.ndarray) -> np.ndarray:
        return np.all(np.abs(positions - self.centre) < self.half, axis=-1).any(axis=1)


def test_palms_low_beside_the_box_rise_before_heading_over_it() -> None:
    # Both palms 4 cm out from the box's +x face, at its centre's height (stepped back after
    # letting it go); the way in heads for set-points 8 cm above the box's -y and +y faces.
    centre, half = np.array([0.55, 0.0, 0.675]), np.array([0.10, 0.15, 0.075])
    world = FakeWorld(objects=[FakeObject("parcel", 2.0 * half)])
    starts = {}
    for arm, side in ((Arm.LEFT, 1.0), (Arm.RIGHT, -1.0)):
        p = np.array([centre[0] + half[0] + 0.04, side * 0.05, centre[2]])
        starts[arm] = measured_state(Pose.of(p, world.rest_palm_pose(arm).orientation), np.zeros(6))
    q = world.rest_palm_pose(Arm.LEFT).orientation
    top = centre[2] + half[2] + 0.08
    waypoints = {
        arm: [
            Pose.of([centre[0], side * (half[1] + 0.08), top], q),
            Pose.of([centre[0], side * (half[1] + 0.04), centre[2]], q),
        ]
        for arm, side in ((Arm.LEFT, 1.0), (Arm.RIGHT, -1.0))
    }
    usual = PalmRoute("coming in from above", waypoints)
    scene = _BoxScene(centre, half)
    straight = predict_palm_path(starts, waypoints, 1.0, DT)
    assert not scene.check_palm_path(straight.positions, straight.orientations, 0.01).clear

    extra = rising_first([usual], starts)
    assert [r.name for r in extra] == ["rising first, then coming in from above"]
    for arm in ARMS:
        first = extra[0].waypoints[arm][0]
        assert_allclose(first.position[:2], starts[arm].position[:2])
        assert first.position[2] == top
        assert list(extra[0].waypoints[arm][1:]) == waypoints[arm]
    chosen = choose_route(scene, starts, [usual, *extra], 1.0, DT, 0.01, detour_of=None)
    assert chosen.clear and chosen.route is extra[0]
    path = predict_palm_path(starts, chosen.route.waypoints, 1.0, DT)
    assert_allclose(path.positions[-1], [w[-1].position for w in waypoints.values()], atol=2e-3)


def test_palms_already_high_take_no_rising_first_route() -> None:
    world = FakeWorld(objects=[FakeObject("parcel", BOX)])
    starts = {a: measured_state(world.palm_pose(a), np.zeros(6)) for a in ARMS}
    route = PalmRoute(
        "usual",
        {
            a: [
                Pose(
                    world.palm_pose(a).position + [0.0, 0.0, RISE_FIRST_M / 2.0],
                    world.palm_pose(a).orientation,
                )
            ]
            for a in ARMS
        },
    )
    assert rising_first([route], starts) == []


class _Recording(FakeWorld):
    """A fake world that records the clearances each palm-path check was asked for."""

    def __init__(self, *args: object, **kwargs: object) -> None:
        super().__init__(*args, **kwargs)  # type: ignore[arg-type]
        self.asked: list[tuple[float, float | None]] = []

    def check_palm_path(
        self,
        palm_positions: np.ndarray,
        palm_orientations: np.ndarray,
        margin_m: float = 0.0,
        object_margin_m: float | None = None,
    ) -> PathCheck:
        self.asked.append((margin_m, object_margin_m))
        return super().check_palm_path(palm_positions, palm_orientations, margin_m)


def test_a_way_in_asks_only_not_touching_objects_a_way_out_the_margin(tick_leaf: Tick) -> None:
    world = _Recording(objects=[FakeObject("parcel", BOX)])
    assert tick_leaf(Approach("approach"), world, object="parcel").final == Status.SUCCESS
    assert world.asked == [(0.01, 0.0)]
    world = _Recording(objects=[FakeObject("parcel", BOX)])
    tick_leaf(Approach("approach"), world, object="parcel", object_margin_m=0.02)
    assert world.asked == [(0.01, 0.02)]
    world = _Recording(objects=[FakeObject("parcel", BOX)])
    assert tick_leaf(Retreat("retreat"), world, back_m=0.04).final == Status.SUCCESS
    assert world.asked == [(0.01, None)]


def test_an_object_over_a_table_lower_than_stated_is_not_said_to_lie_off_it(
    tick_leaf: Tick,
) -> None:
    # Hard mode's table_dz_m of -0.08 put the parcel 8 cm below the stated top, on the table:
    # the reason had said it lay off the table.
    lowered = FakeObject("parcel", BOX, pose=Pose.of([0.6, 0.0, 0.595]))
    log = tick_leaf(Approach("approach"), FakeWorld(objects=[lowered]), object="parcel")
    assert log.final == Status.FAILURE
    assert log.feedback.startswith(
        "parcel lies 0.08 m below the table top the world states, over the table: the table is "
        "lower than stated (or the object beneath it); out of reach"
    )
