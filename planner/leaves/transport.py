"""Transport: the simultaneous composition the reasoner selected, for one move of the task."""

from __future__ import annotations

from typing import ClassVar

import numpy as np
from py_trees.common import Status
from py_trees.ports import PortInformation

from affordances import SemanticAction
from planner.composition import MovePlan, goal_error
from planner.leaves.base import MotionLeaf, composed_move, composition_ports, move_label
from planner.leaves.reflex import reflex_shift
from planner.leaves.set_down import (
    SET_DOWN_SPEED_M_S,
    lowered,
    palm_load_n,
    supported_below_n,
)
from planner.move_result import MoveResult, publish_move_result
from planner.port import Clock, Move, ObjectSensing, ObstacleScene, PalmControl, Pose
from planner.skill_choice import SkillChoiceError
from skills.composer import DualArmComposer, DualArmState
from skills.types import Array
from skills.vocabulary import ARMS

#: How far below the goal the palms search for a surface before the move fails, m.
SET_DOWN_DEPTH_M = 0.05
#: A supported object resting this far above where the composition holds it has met its
#: surface above the goal: the palms' targets rise to it instead of pressing it down, m.
RAISED_SUPPORT_M = 0.01


class Transport(MotionLeaf):
    """Carry the held object to move ``move``'s goal, composing the plan's weighted skills.

    Absolute: the learnt pick-and-place (and rotation) forcing terms, obstacle steering and
    link-level potential-field avoidance, on one transformation system towards the goal.
    Relative: grasp maintenance on each palm, squeezing. Starts from the handed-over full
    state and hands its own on, where it ends, fails or is halted. Fails, explaining why, if
    the grip is lost on the way.

    Succeeds once the composition has arrived (its commanded object at the goal and still,
    after ``tau``) or ``settle_s`` later, and only if the object *as measured* is still and
    within ``tolerance_m`` and ``tolerance_deg`` of the goal (the judge's 2 cm and 10 degrees
    by default); an object that came to rest outside them fails the move, saying where.

    Placing is felt, not only commanded: the goal's height is where the world file says the
    surface is, and a real surface may be elsewhere. An object that arrives still carried by
    the palms (their upward force, :meth:`~planner.port.PalmControl.palm_load`, above
    :func:`~planner.leaves.set_down.supported_below_n`) is lowered at
    :data:`~planner.leaves.set_down.SET_DOWN_SPEED_M_S` until a surface takes it, at most
    :data:`SET_DOWN_DEPTH_M` below the goal; one stopped by a surface
    :data:`RAISED_SUPPORT_M` or more above where it is held has the palms' targets raised to
    it. Either way the goal's height becomes the height
    the object rests at (its x, y and orientation are judged as given), and the handed-over
    state carries the shift.
    Publishes the move's composition and outcome as a :class:`~planner.move_result.MoveResult`
    when it starts and when it ends.

    Runs the composition PathClear checked when one is given (``composition``: it must be of
    this object, move, force and variant, from this ``from_state``); composes the move itself
    otherwise.
    """

    WORLD_ROLES: ClassVar[tuple[type, ...]] = (Clock, ObjectSensing, PalmControl, ObstacleScene)

    INPUT_PORTS = {
        "object": PortInformation(str, description="the held object"),
        "move": PortInformation(int, description="index of the task's move, from 0"),
        "plan": PortInformation(SemanticAction, description="skills and weights to compose"),
        "from_state": PortInformation(DualArmState, description="handed-over full state"),
        "min_force_n": PortInformation(
            float,
            required=False,
            default_value=2.0,
            description="contact force below which the grip is lost, N",
        ),
        **composition_ports(),
        "composition": PortInformation(
            MovePlan,
            required=False,
            description="the move as PathClear composed and checked it; else composed here",
        ),
        "settle_s": PortInformation(
            float,
            required=False,
            default_value=1.0,
            description="time allowed after tau to settle, s",
        ),
        "tolerance_m": PortInformation(
            float,
            required=False,
            default_value=0.02,
            description="largest distance of the measured object from the goal, m",
        ),
        "tolerance_deg": PortInformation(
            float,
            required=False,
            default_value=10.0,
            description="largest angle of the measured object from the goal, degrees",
        ),
    }
    OUTPUT_PORTS = {
        "to_state": PortInformation(DualArmState, description="full state at the end"),
    }

    def initialise(self) -> None:
        """Run the checked composition, or activate the move's obstacles and compose it."""
        self.composer: DualArmComposer | None = None
        self.problem: str | None = None
        #: The palms' targets' present shift away from a near obstacle, m (see _reflex).
        self.reflex_offset: Array = np.zeros(3)
        inputs = self.object_and_move()
        if isinstance(inputs, str):
            self.problem = inputs
            return
        world = self.world
        name, index = inputs
        plan: SemanticAction = self.get_input("plan")
        force = self.palm_squeeze_force(plan)
        state: DualArmState = self.get_input("from_state")
        avoid_gain = float(self.get_input("avoid_gain"))
        transport_weight = float(self.get_input("transport_weight"))
        hold_gain = float(self.get_input("hold_gain"))
        skill: str | None = self.optional_input("skill")
        checked: MovePlan | None = self.optional_input("composition")
        above_fixture = bool(self.get_input("above_fixture"))
        if checked is None:
            try:
                checked = composed_move(self, name, index)
            except SkillChoiceError as err:
                self.problem = str(err)
                return
        else:
            ours = {
                "object": name,
                "move": index,
                "force_n": force,
                "avoid_gain": avoid_gain,
                "transport_weight": transport_weight,
                "hold_gain": hold_gain,
                "skill": skill,
                "above_fixture": above_fixture,
            }
            theirs = (
                checked.object,
                checked.index,
                checked.squeeze_force_n,
                checked.avoid_gain,
                checked.transport_weight,
                checked.hold_gain,
                checked.requested_skill,
                checked.above_fixture,
            )
            wrong = [
                f"{port} {value!r}, checked with {other!r}"
                for (port, value), other in zip(ours.items(), theirs, strict=True)
                if value != other
            ]
            if checked.from_state is not state:
                wrong.append("from_state is not the state it was checked from")
            if wrong:
                self.problem = "not the composition of this move: " + "; ".join(wrong)
                return
        self.move: Move = checked.move
        self.skill = checked.skill
        #: Ends held above a fixture (Insert lowers it in): no set-down by feel.
        self.hovering = checked.above_fixture and checked.move.fixture is not None
        # The ports a running carry reads every tick, read once as it starts (a port's value
        # does not change under a running move; the blackboard's checks cost more than a step).
        self.object_name = name
        self.move_index = index
        self.move_label = move_label(world.task_moves(name), name, index)
        self.min_force_n = float(self.get_input("min_force_n"))
        self.settle_s = float(self.get_input("settle_s"))
        self.tolerance = (
            float(self.get_input("tolerance_m")),
            float(self.get_input("tolerance_deg")),
        )
        #: Weight below which the palms no longer carry the object, N.
        self.supported_below_n = supported_below_n(world, name)
        #: Shift of the palms' targets along world z from the composition's, m (set-down).
        self.lift_offset = 0.0
        self.set_down_from: float | None = None  # when the set-down began, s
        self.composer = checked.fresh()
        self.started = world.time()
        self.weak_ticks = 0
        self._publish(Status.RUNNING)

    def update(self) -> Status:
        """One composition step; SUCCESS at the goal and still; FAILURE if the grip is lost."""
        if self.problem is not None:
            return self.fail(self.problem)
        assert self.composer is not None
        world = self.world
        name = self.object_name
        cmd = self.composer.step(self.control_dt)
        away = self._reflex(name)
        for i, arm in enumerate(ARMS):
            position = cmd.positions[i] + away
            if self.lift_offset:
                position = position + np.array([0.0, 0.0, self.lift_offset])
            world.command_palm(arm, Pose(position, cmd.orientations[i]), cmd.twists[i])
        forces = [world.contact_force(arm, name) for arm in ARMS]
        if min(forces) < self.min_force_n:
            self.weak_ticks += 1
            if self.weak_ticks * self.control_dt > 0.1:
                return self.fail(
                    f"grip lost: contact forces {forces[0]:.1f} N and {forces[1]:.1f} N"
                )
        else:
            self.weak_ticks = 0
        elapsed = world.time() - self.started
        tau = self.composer.target.tau
        # The composition has arrived when its commanded object is at the goal and still ...
        commanded = self.composer.state.object
        arrived = (
            elapsed >= tau
            and np.linalg.norm(commanded.position - self.move.goal.position) < 2e-3
            and np.linalg.norm(commanded.velocity) < 5e-3
        )
        settled = elapsed > tau + self.settle_s
        if arrived or settled:
            # A carry to above a fixture arrives still carried on purpose: Insert lowers it.
            lowering = None if self.hovering else self._set_down(name, commanded.position[2])
            if lowering is not None:
                return lowering
            # ... but the move is judged on the object as measured: a held object hangs below
            # its commanded pose, and only the measured pose is where it was put.
            twist = world.object_twist(name)
            still = np.linalg.norm(twist[:3]) < 5e-3 and np.linalg.norm(twist[3:]) < 0.05
            err_m, err_rad = goal_error(world, name, self._placed_goal(name))
            tol_m, tol_deg = self.tolerance
            within = err_m <= tol_m and np.degrees(err_rad) <= tol_deg
            off = f"{err_m * 1000:.1f} mm, {np.degrees(err_rad):.1f} deg from the goal"
            if still and within:
                self._set_output("to_state", self._handed_over())
                return self.succeed(f"{'placed' if arrived else 'settled'} {off}")
            if settled and still:
                return self.fail(
                    f"came to rest {off} (tolerance {tol_m * 1000:.0f} mm, {tol_deg:g} deg)"
                )
        return self.running(
            f"{self.move_label}: {elapsed:.1f} of {tau:.1f} s (move={self.move_index})"
        )

    def _reflex(self, name: str) -> Array:
        """The shift of both palms' targets, (3,) m, away from a near obstacle
        (:func:`planner.leaves.reflex.reflex_shift`). The composition itself runs on: its
        state, and the state handed over, are the commanded ones."""
        self.reflex_offset = reflex_shift(self.world, name, self.reflex_offset, self.control_dt)
        return self.reflex_offset

    def _set_down(self, name: str, commanded_z: float) -> Status | None:
        """RUNNING while the palms lower an object no surface carries yet (or FAILURE once
        they searched :data:`SET_DOWN_DEPTH_M` below the goal); None once one does. Raises the
        targets to an object resting above where it is held (see the class)."""
        world = self.world
        load = palm_load_n(world, name)
        if load > self.supported_below_n:
            if self.set_down_from is None:
                self.set_down_from = world.time()
            depth = SET_DOWN_SPEED_M_S * (world.time() - self.set_down_from)
            if depth > SET_DOWN_DEPTH_M:
                return self.fail(
                    f"no surface took the object within {SET_DOWN_DEPTH_M * 1000:.0f} mm below "
                    f"the goal (the palms still carry {load:.1f} N)"
                )
            self.lift_offset = -depth
            return self.running(f"setting down: {depth * 1000:.0f} mm below the goal")
        resting_z = float(world.object_pose(name).position[2])
        if resting_z - (commanded_z + self.lift_offset) >= RAISED_SUPPORT_M:
            self.lift_offset = resting_z - commanded_z
        return None

    def _placed_goal(self, name: str) -> Pose:
        """The move's goal; after a set-down, at the height the object rests at."""
        goal = self.move.goal
        if not self.lift_offset:
            return goal
        resting_z = float(self.world.object_pose(name).position[2])
        return Pose(np.array([*goal.position[:2], resting_z]), goal.orientation)

    def _rested_z(self, name: str) -> float | None:
        """The height the object was placed at when it is not the task's goal's (a set-down
        felt the surface elsewhere, or the goal was raised with a table found off its stated
        height), for AtGoal; else None (and for a carry that ends above a fixture)."""
        if self.hovering:
            return None
        placed_z = float(self._placed_goal(name).position[2])
        stated_z = float(self.world.task_moves(name)[self.move_index].goal.position[2])
        return placed_z if abs(placed_z - stated_z) > 1e-9 else None

    def _handed_over(self) -> DualArmState:
        """The composition's full state, shifted by the set-down."""
        assert self.composer is not None
        state = self.composer.state
        if not self.lift_offset:
            return state
        return lowered(state, -self.lift_offset, -state.object.velocity[2])

    def terminate(self, new_status: Status) -> None:
        """Publish how the started move ended (:mod:`planner.move_result`); halted, stop.

        A move that failed or was halted part-way hands over the state it left the palms in,
        as a finished one does: whatever runs next (another composition of the move, a
        re-grasp) starts from there. The state it was handed would hold the palms' references
        from before it moved, and a composition started from that drags the object back.
        """
        started = getattr(self, "composer", None) is not None
        if started and (new_status != Status.INVALID or self.status == Status.RUNNING):
            if new_status != Status.SUCCESS:
                self._set_output("to_state", self._handed_over())
            self._publish(new_status)
        super().terminate(new_status)

    def _publish(self, status: Status) -> None:
        name = self.get_input("object")
        err_m, err_rad = (
            goal_error(self.world, name, self.move.goal)
            if status == Status.SUCCESS
            else (None, None)
        )
        publish_move_result(
            MoveResult(
                name,
                int(self.get_input("move")),
                float(self.get_input("transport_weight")),
                float(self.get_input("avoid_gain")),
                status,
                err_m,
                err_rad,
                self.skill,
                self._rested_z(name) if status == Status.SUCCESS else None,
            ),
            self.name,
        )
