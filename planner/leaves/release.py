"""Release and Retreat: open the palms off the object's faces, then take the arms away."""

from __future__ import annotations

from typing import ClassVar

import numpy as np
from py_trees.common import Status
from py_trees.ports import PortInformation

from planner.composition import held_lateral_geometry, opening_terms, static_composition
from planner.leaves.base import MotionLeaf
from planner.leaves.palm_motion import ViaPointLeaf, ViaPointMotion, measured_state
from planner.port import Clock, ObjectSensing, PalmControl, Pose
from skills.composer import DualArmComposer, DualArmState
from skills.vocabulary import ARMS


class Release(MotionLeaf):
    """Move each palm ``opening_m`` out along its contact normal (a relative skill)."""

    WORLD_ROLES: ClassVar[tuple[type, ...]] = (Clock, ObjectSensing, PalmControl)

    INPUT_PORTS = {
        "object": PortInformation(str, description="the held object"),
        "from_state": PortInformation(DualArmState, description="handed-over full state"),
        "opening_m": PortInformation(
            float,
            required=False,
            default_value=0.05,
            description="gap to open between palm and face, m",
        ),
        "open_s": PortInformation(
            float, required=False, default_value=1.0, description="time scale of opening, s"
        ),
    }
    OUTPUT_PORTS = {
        "to_state": PortInformation(DualArmState, description="full state after opening"),
    }

    def initialise(self) -> None:
        """Compose the opening from the handed-over state."""
        self.composer: DualArmComposer | None = None
        if self.connected() is not None:
            return
        name = self.get_input("object")
        state = self.get_input("from_state")
        relative = opening_terms(
            held_lateral_geometry(self.world, name, state),
            float(self.get_input("opening_m")),
        )
        self.composer = static_composition(state, relative, float(self.get_input("open_s")))
        self.started = self.world.time()

    def update(self) -> Status:
        """RUNNING while opening; SUCCESS when out of contact and still."""
        if (why := self.connected()) is not None:
            return self.fail(why)
        assert self.composer is not None
        world = self.world
        cmd = self.composer.step(self.control_dt)
        for i, arm in enumerate(ARMS):
            world.command_palm(arm, Pose(cmd.positions[i], cmd.orientations[i]), cmd.twists[i])
        forces = [world.contact_force(arm, self.get_input("object")) for arm in ARMS]
        st = self.composer.state
        still = max(np.linalg.norm(st.left.velocity), np.linalg.norm(st.right.velocity)) < 5e-3
        if max(forces) < 0.5 and still and world.time() - self.started > 0.3:
            self._set_output("to_state", st)
            return self.succeed("palms open and clear of the object")
        return self.running(f"opening: {forces[0]:.1f} N, {forces[1]:.1f} N")


class Retreat(ViaPointLeaf):
    """Take both palms back to their rest poses, rising first."""

    WORLD_ROLES: ClassVar[tuple[type, ...]] = (PalmControl,)

    INPUT_PORTS = {
        "rise_m": PortInformation(
            float,
            required=False,
            default_value=0.1,
            description="height to rise before going back, m",
        ),
        "segment_s": PortInformation(
            float,
            required=False,
            default_value=1.5,
            description="duration scale of each segment, s",
        ),
    }
    OUTPUT_PORTS: dict[str, PortInformation] = {}
    MOVING = "retreating"
    ARRIVED = "palms at rest"

    def initialise(self) -> None:
        """Plan rise-then-rest from where the palms are."""
        self.motion = None
        if self.connected() is not None:
            return
        world = self.world
        rise = np.array([0.0, 0.0, float(self.get_input("rise_m"))])
        waypoints = {}
        for arm in ARMS:
            here = world.palm_pose(arm)
            waypoints[arm] = [
                Pose(here.position + rise, here.orientation),
                world.rest_palm_pose(arm),
            ]
        starts = {a: measured_state(world.palm_pose(a), world.palm_twist(a)) for a in ARMS}
        self.motion = ViaPointMotion(starts, waypoints, float(self.get_input("segment_s")))
