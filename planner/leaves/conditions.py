"""Condition leaves: IsHeld, AtGoal, PathClear. They answer in one tick, never RUNNING."""

from __future__ import annotations

import dataclasses
from typing import ClassVar

import numpy as np
from py_trees.common import Status
from py_trees.ports import PortInformation

from affordances import SemanticAction
from planner.composition import MovePlan, goal_error
from planner.leaves.base import WorldLeaf, composed_move, composition_ports
from planner.move_result import move_placements, move_results, publish_move_result
from planner.port import ObjectSensing, ObstacleScene, PalmControl, Pose
from planner.skill_choice import SkillChoiceError
from skills.composer import DualArmState, relative_from_world
from skills.dual_arm import shift_along_face
from skills.vocabulary import ARMS


class IsHeld(WorldLeaf):
    """Both palms press on the object and, given the grasp's state, have not slipped along its
    faces from where the grasp put them (the object knocked, dropped or turned in the grip).

    The default ``max_slip_m`` (5 cm) is well above what carrying does to a sound grip: turned
    grips shift their palms 20-36 mm along the faces (the default world's turned-goal trials,
    where letting go and grasping again made things worse), a shove that knocks the parcel
    out 130 mm.
    """

    WORLD_ROLES: ClassVar[tuple[type, ...]] = (ObjectSensing, PalmControl)

    NODE_TYPE: ClassVar[str] = "Condition"
    INPUT_PORTS = {
        "object": PortInformation(str, description="the object that should be held"),
        "min_force_n": PortInformation(
            float, required=False, default_value=2.0, description="least contact force per palm, N"
        ),
        "max_slip_m": PortInformation(
            float,
            required=False,
            default_value=0.05,
            description="largest move of a palm along its face from the grasp's reference, m",
        ),
        "from_state": PortInformation(
            DualArmState,
            required=False,
            description="the state the last skill handed over: its palms in the object frame "
            "are the grasp's reference",
        ),
    }
    OUTPUT_PORTS: dict[str, PortInformation] = {}

    def update(self) -> Status:
        """SUCCESS if held, FAILURE with the forces or the slip otherwise."""
        if (why := self.connected()) is not None:
            return self.fail(why)
        name = self.get_input("object")
        forces = [self.world.contact_force(arm, name) for arm in ARMS]
        least = float(self.get_input("min_force_n"))
        if min(forces) < least:
            return self.fail(
                f"not held: contact forces {forces[0]:.1f} N, {forces[1]:.1f} N "
                f"(need {least:g} N each)"
            )
        reference: DualArmState | None = self.optional_input("from_state")
        if reference is not None:
            obj = self.world.object_pose(name)
            slips = []
            for arm in ARMS:
                palm = self.world.palm_pose(arm)
                local, _ = relative_from_world(
                    obj.position, obj.orientation, palm.position, palm.orientation
                )
                slips.append(float(shift_along_face(local, reference.relative(arm).position)))
            worst = int(np.argmax(slips))
            if slips[worst] > float(self.get_input("max_slip_m")):
                return self.fail(
                    f"slipped in the grip: the {ARMS[worst].value} palm "
                    f"{slips[worst] * 1000:.1f} mm along its face from the grasp"
                )
        return self.succeed(f"held: {forces[0]:.1f} N, {forces[1]:.1f} N")


class AtGoal(WorldLeaf):
    """The object is within tolerance of a move's goal pose (at the height its last
    successful Transport set it down at, when it felt the surface elsewhere:
    :attr:`~planner.move_result.MoveResult.rested_z`; at the place its Insert seated it, when
    it found the fixture elsewhere: :attr:`~planner.move_result.MoveResult.found_xy`).

    A move whose carry is running or was halted, with no placement yet, is placed where this
    finds it: the move's result is published as SUCCESS with the
    errors measured here, as the judge and the records read placements."""

    WORLD_ROLES: ClassVar[tuple[type, ...]] = (ObjectSensing,)

    NODE_TYPE: ClassVar[str] = "Condition"
    INPUT_PORTS = {
        "object": PortInformation(str, description="the object"),
        "move": PortInformation(int, description="index of the task's move, from 0"),
        "tolerance_m": PortInformation(
            float, required=False, default_value=0.02, description="position tolerance, m"
        ),
        "tolerance_deg": PortInformation(
            float, required=False, default_value=10.0, description="orientation tolerance, degrees"
        ),
    }
    OUTPUT_PORTS: dict[str, PortInformation] = {}

    def update(self) -> Status:
        """SUCCESS within tolerance; FAILURE naming the errors otherwise."""
        inputs = self.object_and_move()
        if isinstance(inputs, str):
            return self.fail(inputs)
        name, index = inputs
        goal = self.world.task_moves(name)[index].goal
        placed = move_placements().get((name, index))
        if placed is not None and placed.rested_z is not None:
            # Its Transport felt the surface elsewhere than the goal's height: the goal is the
            # same place on the surface as found.
            goal = Pose(np.array([*goal.position[:2], placed.rested_z]), goal.orientation)
        if placed is not None and placed.found_xy is not None:
            # Its Insert found the fixture by touch elsewhere than the goal's place.
            goal = Pose(np.array([*placed.found_xy, goal.position[2]]), goal.orientation)
        err_m, err_rad = goal_error(self.world, name, goal)
        deg = float(np.degrees(err_rad))
        text = f"{err_m * 1000:.1f} mm and {deg:.1f} deg from goal {index}"
        tol_m, tol_deg = (
            float(self.get_input("tolerance_m")),
            float(self.get_input("tolerance_deg")),
        )
        if err_m <= tol_m and deg <= tol_deg:
            self._place_halted_carry(name, index, err_m, err_rad)
            return self.succeed(text)
        return self.fail(text)

    def _place_halted_carry(self, name: str, index: int, err_m: float, err_rad: float) -> None:
        """A carry found at the goal while it runs (a reactive parent then halts it:
        ``ReactiveFallback(AtGoal, Transport)``) or after it was halted is the move's
        placement, measured here: publish it as the Transport would have, unless the move was
        placed before."""
        latest = move_results().get((name, index))
        halted = latest is not None and latest.status in (Status.RUNNING, Status.INVALID)
        if latest is None or not halted or (name, index) in move_placements():
            return
        placed = dataclasses.replace(
            latest, status=Status.SUCCESS, placement_error_m=err_m, placement_error_rad=err_rad
        )
        publish_move_result(placed, self.name)


class PathClear(WorldLeaf):
    """The predicted rollout of a move's composition keeps clear of the obstacles (FCL).

    Composes the move (which activates its obstacles), rolls a copy out open loop and checks
    it; on SUCCESS writes the composition it checked to ``composition``, for Transport to run.
    """

    WORLD_ROLES: ClassVar[tuple[type, ...]] = (ObjectSensing, PalmControl, ObstacleScene)

    NODE_TYPE: ClassVar[str] = "Condition"
    INPUT_PORTS = {
        "object": PortInformation(str, description="the held object"),
        "move": PortInformation(int, description="index of the task's move, from 0"),
        "plan": PortInformation(SemanticAction, description="skills and weights to compose"),
        "from_state": PortInformation(DualArmState, description="state the move starts from"),
        **composition_ports(),
        "margin_m": PortInformation(
            float, required=False, default_value=0.0, description="clearance required, m"
        ),
        "link_doubt": PortInformation(
            bool,
            required=False,
            default_value=True,
            description="ask the arms' predicted links the extra clearance the world's doubt "
            "of their prediction adds (growing with the palms' travel); false: margin_m alone, "
            "refusing only a path whose predicted links touch (a last resort's check)",
        ),
    }
    OUTPUT_PORTS = {
        "composition": PortInformation(
            MovePlan, description="the move's composition as checked, at its start state"
        ),
    }

    def update(self) -> Status:
        """Roll the composition out open loop and check it; SUCCESS if clear."""
        inputs = self.object_and_move()
        if isinstance(inputs, str):
            return self.fail(inputs)
        name, index = inputs
        world = self.world
        try:
            checked = composed_move(self, name, index)
        except SkillChoiceError as err:
            return self.fail(str(err))
        n = int(np.ceil((checked.composer.target.tau + 0.5) / self.control_dt))
        path = checked.fresh().rollout(n, self.control_dt)
        obj_p = path.object_positions
        check = world.check_trajectory(
            name,
            obj_p,
            path.object_orientations,
            path.palm_positions,
            path.palm_orientations,
            float(self.get_input("margin_m")),
            link_doubt=bool(self.get_input("link_doubt")),
        )
        if check.clear:
            self._set_output("composition", checked)
            return self.succeed(
                f"clear by {float(self.get_input('margin_m')) * 1000:.0f} mm or more over {n} "
                f"steps (object centre and palms {check.min_distance_m * 1000:.0f} mm from the "
                "nearest obstacle)"
            )
        k = check.first_collision or 0
        where = np.round(obj_p[k], 3).tolist()
        return self.fail(
            f"predicted collision at step {k} (object at {where}, "
            f"palms at {np.round(path.palm_positions[k], 3).tolist()}): {check.detail}"
        )
