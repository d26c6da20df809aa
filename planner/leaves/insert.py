"""Insert: lower a held box from above a fixture into it, under compliance (eq. 5 + admittance)."""

from __future__ import annotations

from typing import ClassVar

import numpy as np
from py_trees.common import Status
from py_trees.ports import PortInformation

from affordances import SemanticAction
from planner.composition import goal_error, transport_composition
from planner.leaves.base import MotionLeaf
from planner.leaves.set_down import palm_load_n, supported_below_n
from planner.move_result import MoveResult, publish_move_result
from planner.port import Clock, Move, ObjectSensing, ObstacleScene, PalmControl, Pose
from skills.composer import DualArmComposer, DualArmState
from skills.insertion import MAX_SHIFT_M, SEARCH_SPEED_M_S, AdmittanceGains, admittance_step
from skills.types import Array
from skills.vocabulary import ARMS, Action

#: How fast the palms go on down once the learnt descent has ended with the box still carried
#: (it may hang a little in the grip), m/s, and how far, m.
PRESS_SPEED_M_S = 0.01
PRESS_DEPTH_M = 0.02


class Insert(MotionLeaf):
    """Lower the held box from above its fixture into it, yielding to the walls.

    The plan's insertion (:class:`~skills.vocabulary.Action` ``INSERT``, which the reasoner
    selects for a move whose goal is in a fixture; the library's learnt descent so labelled)
    is composed with the plan's other skills towards the move's seated goal
    (:func:`planner.composition.transport_composition`, eq. 5), from the handed-over state
    (the box held above the fixture by a Transport with ``above_fixture``). Each control step
    the fixture's force on the box (:meth:`~planner.port.ObjectSensing.fixture_force`) and
    its torque about the box's centre (:meth:`~planner.port.ObjectSensing.fixture_torque`)
    couple in (:func:`skills.insertion.admittance_step`, gains the skill's): the palms'
    targets shift sideways away from a wall pressing the box and towards where the
    composition wants the box, search off a wall's top the box came down on, and the
    descent's phase slows, or stops while the force exceeds the bound.

    Not a set-down by feel: Transport's (:mod:`planner.leaves.transport`) is off for the carry
    that ends above the fixture. Succeeds once the descent has ended and the box rests (the
    palms no longer carry it) at the goal's height within ``tolerance_m``, turned within
    ``tolerance_deg`` of it, and sideways no farther from it than the coupling may shift it
    (``max_shift`` plus ``tolerance_m``: a fixture that stands off where the robot was told
    seats the box where it truly is; at the goal's height the box is inside its walls); a
    box still carried then is pressed on down at :data:`PRESS_SPEED_M_S`, at most
    :data:`PRESS_DEPTH_M`. Fails, saying why, if the plan selects no insertion, the grip is
    lost or the box rests elsewhere.
    """

    WORLD_ROLES: ClassVar[tuple[type, ...]] = (Clock, ObjectSensing, PalmControl, ObstacleScene)

    INPUT_PORTS = {
        "object": PortInformation(str, description="the held object"),
        "move": PortInformation(int, description="index of the task's move into a fixture"),
        "plan": PortInformation(SemanticAction, description="skills and weights to compose"),
        "from_state": PortInformation(DualArmState, description="handed-over full state"),
        "force_n": PortInformation(
            float, required=False, default_value=25.0, description="squeeze per palm, N"
        ),
        "min_force_n": PortInformation(
            float,
            required=False,
            default_value=2.0,
            description="contact force below which the grip is lost, N",
        ),
        "tolerance_m": PortInformation(
            float, required=False, default_value=0.003, description="seated within, m"
        ),
        "tolerance_deg": PortInformation(
            float, required=False, default_value=3.0, description="seated within, degrees"
        ),
        "settle_s": PortInformation(
            float,
            required=False,
            default_value=1.0,
            description="time allowed after the descent to come to rest, s",
        ),
    }
    OUTPUT_PORTS = {
        "to_state": PortInformation(DualArmState, description="full state at the end"),
    }

    def initialise(self) -> None:
        """Compose the descent to the seated goal with the learnt insertion skill."""
        self.composer: DualArmComposer | None = None
        self.problem: str | None = None
        inputs = self.object_and_move()
        if isinstance(inputs, str):
            self.problem = inputs
            return
        world = self.world
        name, index = inputs
        move: Move = world.task_moves(name)[index]
        if move.fixture is None:
            self.problem = f"move {index} of {name!r} goes into no fixture"
            return
        plan: SemanticAction = self.get_input("plan")
        selected = plan.skill(Action.INSERT)
        if selected is None:
            self.problem = (
                f"the plan for {name!r} selects no {Action.INSERT.value} skill (it has "
                f"{', '.join(a.value for a in plan.actions)}): move {index} goes into fixture "
                f"{move.fixture!r}, which the reasoner's plan must say"
            )
            return
        try:
            skill = self.library.first(Action.INSERT, selected.space)
        except KeyError:
            self.problem = (
                f"the library has no {Action.INSERT.value} skill in {selected.space.value} "
                f"space for the plan's insertion (its skills: {', '.join(self.library.names())})"
            )
            return
        p = skill.params
        self.gains = AdmittanceGains(
            float(p["compliance"]),
            float(p["centring"]),
            float(p["soft_force_n"]),
            float(p["stop_force_n"]),
            search_speed=float(p.get("search_speed", SEARCH_SPEED_M_S)),
            max_shift=float(p.get("max_shift", MAX_SHIFT_M)),
        )
        world.set_active_obstacles(move.obstacles)
        self.composer = transport_composition(
            plan,
            self.library,
            world,
            name,
            move,
            self.get_input("from_state"),
            self.palm_squeeze_force(plan),
            skill=skill.name,
        )
        self.move = move
        self.name_ = name
        self.offset: Array = np.zeros(2)
        self.press = 0.0
        self.phase_time = 0.0
        self.ended_at: float | None = None
        self.weak_ticks = 0
        self.peak_force = 0.0
        self.found_xy: tuple[float, float] | None = None
        self.min_force_n = float(self.get_input("min_force_n"))
        self.supported_below_n = supported_below_n(world, name)
        self.index = index
        self.skill_name = skill.name
        self._publish(Status.RUNNING)

    def update(self) -> Status:
        """One step of the coupled descent; SUCCESS seated; FAILURE off the goal or dropped."""
        if self.problem is not None:
            return self.fail(self.problem)
        assert self.composer is not None
        world, name, dt = self.world, self.name_, self.control_dt
        force = world.fixture_force(name)
        self.peak_force = max(self.peak_force, float(np.linalg.norm(force)))
        commanded = self.composer.state.object.position
        error = commanded[:2] - world.object_pose(name).position[:2]
        self.offset, rate = admittance_step(
            self.offset, force, error, self.gains, dt, world.fixture_torque(name)
        )
        cmd = self.composer.step(dt * rate)
        self.phase_time += dt * rate
        shift = np.array([*self.offset, -self.press])
        for i, arm in enumerate(ARMS):
            world.command_palm(
                arm, Pose(cmd.positions[i] + shift, cmd.orientations[i]), cmd.twists[i]
            )
        forces = [world.contact_force(arm, name) for arm in ARMS]
        if min(forces) < self.min_force_n:
            self.weak_ticks += 1
            if self.weak_ticks * dt > 0.1:
                return self.fail(f"grip lost: contact forces {forces[0]:.1f} N, {forces[1]:.1f} N")
        else:
            self.weak_ticks = 0
        tau = self.composer.target.tau
        if self.phase_time < tau:
            return self.running(f"inserting: {self.phase_time:.1f} of {tau:.1f} s")
        if self.ended_at is None:
            self.ended_at = world.time()
        load = palm_load_n(world, name)
        if load > self.supported_below_n and rate > 0.0:
            self.press = min(self.press + PRESS_SPEED_M_S * dt * rate, PRESS_DEPTH_M)
        twist = world.object_twist(name)
        still = np.linalg.norm(twist[:3]) < 5e-3 and np.linalg.norm(twist[3:]) < 0.05
        _, err_rad = goal_error(world, name, self.move.goal)
        err = world.object_pose(name).position - np.asarray(self.move.goal.position)
        tol_m, tol_deg = (
            float(self.get_input("tolerance_m")),
            float(self.get_input("tolerance_deg")),
        )
        aside = float(np.linalg.norm(err[:2]))
        off = (
            f"{err[2] * 1000:.1f} mm above and {aside * 1000:.1f} mm aside of the seated goal, "
            f"{np.degrees(err_rad):.1f} deg"
        )
        if (
            still
            and load <= self.supported_below_n
            and abs(err[2]) <= tol_m
            and aside <= self.gains.max_shift + tol_m
            and np.degrees(err_rad) <= tol_deg
        ):
            if aside > tol_m:  # the fixture stands elsewhere than the goal: where it seated
                position = world.object_pose(name).position
                self.found_xy = (float(position[0]), float(position[1]))
            self._set_output("to_state", self.composer.state)
            return self.succeed(f"seated {off} (peak fixture force {self.peak_force:.1f} N)")
        if (
            world.time() - self.ended_at
            > float(self.get_input("settle_s")) + PRESS_DEPTH_M / PRESS_SPEED_M_S
        ):
            return self.fail(f"not seated: {off}, palms carry {load:.1f} N")
        return self.running(f"seating: {off}")

    def terminate(self, new_status: Status) -> None:
        """Publish how the started insertion ended (the move's result); halted, stop."""
        started = getattr(self, "composer", None) is not None
        if started and (new_status != Status.INVALID or self.status == Status.RUNNING):
            self._publish(new_status)
        super().terminate(new_status)

    def _publish(self, status: Status) -> None:
        """The move's :class:`~planner.move_result.MoveResult`: the seated pose's error at
        SUCCESS (it replaces the carry's, which ended above the fixture)."""
        err_m, err_rad = (
            goal_error(self.world, self.name_, self.move.goal)
            if status == Status.SUCCESS
            else (None, None)
        )
        publish_move_result(
            MoveResult(
                self.name_,
                self.index,
                1.0,
                1.0,
                status,
                err_m,
                err_rad,
                self.skill_name,
                found_xy=self.found_xy if status == Status.SUCCESS else None,
            ),
            self.name,
        )
