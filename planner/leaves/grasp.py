"""Grasp: close both palms on the object's faces, then squeeze until the force is reached."""

from __future__ import annotations

from typing import ClassVar

import numpy as np
from py_trees.common import Status
from py_trees.ports import PortInformation

from affordances import SemanticAction
from planner.composition import static_composition
from planner.grips import facing_quarter_turns, grasp_quarter_turns, lateral_geometry, move_turn
from planner.held_states import closing_dual_state
from planner.leaves.base import SQUEEZE_FORCE_N, MotionLeaf, grasp_move_port
from planner.leaves.reflex import reflex_shift
from planner.port import Clock, ObjectSensing, ObstacleScene, PalmControl, Pose
from planner.skill_terms import hold_terms
from skills.composer import DualArmComposer, DualArmState, relative_from_world
from skills.pose_dmp import PoseState
from skills.types import Array
from skills.vocabulary import ARMS


def anchored(composer: DualArmComposer, measured: Pose, shift: Array | None = None) -> DualArmState:
    """The grasp's state with {O} moved onto the measured object, palm references unchanged
    but for ``shift`` (3,) m, the obstacle reflex's on both palms' commands (none: zero).

    Closing can nudge the object; from here on the object's frame must be where it really
    is, so that transports put the object (not an idealised grip) on the goal. The palms'
    world references stay as they are, so the commands do not jump.

    Horizontally {O} is put midway between the palms' references: a box closed on off
    centre (a palm that met its face first pushed it, and the table's friction holds it there)
    slides to where the two squeezes balance as soon as it is lifted, and that is where the
    transports must carry it from. Its height and orientation are the measured ones.

    With a ``shift`` the palms were sent that far from the composition's references (the
    obstacle reflex, :mod:`planner.leaves.reflex`): the state handed on holds them where they
    were sent, so the next skill does not pull the object back towards the obstacle.
    """
    cmd = composer.commands()
    palms = [np.asarray(p, dtype=float) + (0.0 if shift is None else shift) for p in cmd.positions]
    centre = np.asarray(measured.position, dtype=float).copy()
    centre[:2] = 0.5 * (palms[0][:2] + palms[1][:2])
    measured = Pose(centre, measured.orientation)
    rel = [
        relative_from_world(measured.position, measured.orientation, palms[i], cmd.orientations[i])
        for i in range(2)
    ]
    return DualArmState(
        PoseState.at_rest(measured.position, measured.orientation),
        PoseState.at_rest(*rel[0]),
        PoseState.at_rest(*rel[1]),
    )


class Grasp(MotionLeaf):
    """Lateral contact, then squeeze: grasp maintenance pulls the palms onto the faces the
    palms stand beside, as :class:`~planner.leaves.Approach` left them; palms that stand beside
    none close on the pair that suits move ``move``'s turn.

    Closing can push the object: a palm that meets its face first (the object sensed off its
    true pose, or an actuator biased) shoves it until the other palm arrives. Near an
    obstacle, that shove ends in it; so, as Transport does, the leaf shifts both palms'
    targets away from an obstacle the object comes near
    (:func:`~planner.leaves.reflex.reflex_shift`), and hands the state on where the palms
    were sent.

    A palm that already presses the object when closing starts (at the pre-grasp pose a
    biased actuator can hold it centimetres off its target, into the face) closes from where
    it was sent, not from where it is (:func:`~planner.held_states.closing_dual_state`): a
    reference moved onto it would let the bias push it that much further into the face at
    once.
    """

    WORLD_ROLES: ClassVar[tuple[type, ...]] = (Clock, ObjectSensing, PalmControl, ObstacleScene)

    INPUT_PORTS = {
        "object": PortInformation(str, description="object to grasp"),
        "move": grasp_move_port(),
        "force_n": PortInformation(
            float,
            required=False,
            default_value=SQUEEZE_FORCE_N,
            description="squeeze force per palm to reach, N",
        ),
        "plan": PortInformation(
            SemanticAction,
            required=False,
            description="the plan; its hold skill may ask for more force",
        ),
        "close_s": PortInformation(
            float, required=False, default_value=1.0, description="time scale of closing, s"
        ),
    }
    OUTPUT_PORTS = {
        "state": PortInformation(DualArmState, description="full state handed to the next skill"),
    }

    def initialise(self) -> None:
        """Start the relative composition from the palms (a pressing one where it was sent)."""
        self.composer: DualArmComposer | None = None
        if self.connected() is not None:
            return
        world = self.world
        name = self.get_input("object")
        self.force = self.palm_squeeze_force(self.optional_input("plan"))
        depth = world.squeeze_depth(self.force)
        # The faces the palms stand beside (an approach may have taken other faces than the
        # usual pair, the usual one's way in ending on an obstacle); else the usual pair.
        k = facing_quarter_turns(world, name)
        if k is None:
            k = grasp_quarter_turns(
                world, name, move_turn(world, name, int(self.get_input("move")))
            )
        geometry = lateral_geometry(world, name, k)
        relative = hold_terms(self.optional_input("plan"), self.library, geometry, depth)
        self.composer = static_composition(
            closing_dual_state(world, name),
            relative,
            float(self.get_input("close_s")),
        )
        self.started = world.time()
        #: Both palms' targets' present shift away from a near obstacle, m.
        self.reflex_offset: Array = np.zeros(3)

    def update(self) -> Status:
        """RUNNING while closing; SUCCESS once both palms press with the force."""
        if (why := self.connected()) is not None:
            return self.fail(why)
        assert self.composer is not None
        world = self.world
        name = self.get_input("object")
        cmd = self.composer.step(self.control_dt)
        self.reflex_offset = reflex_shift(world, name, self.reflex_offset, self.control_dt)
        for i, arm in enumerate(ARMS):
            position = cmd.positions[i] + self.reflex_offset
            world.command_palm(arm, Pose(position, cmd.orientations[i]), cmd.twists[i])
        forces = [world.contact_force(arm, name) for arm in ARMS]
        settled = world.time() - self.started > 0.5
        if settled and min(forces) >= 0.8 * self.force:
            state = anchored(self.composer, world.object_pose(name), self.reflex_offset)
            self._set_output("state", state)
            return self.succeed(f"squeezing {forces[0]:.1f} N and {forces[1]:.1f} N")
        return self.running(f"closing: {forces[0]:.1f} N, {forces[1]:.1f} N of {self.force:.1f}")
