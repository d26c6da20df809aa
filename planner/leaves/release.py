"""Release and Retreat: open the palms off the object's faces, then take the arms away."""

from __future__ import annotations

from typing import ClassVar

import numpy as np
from py_trees.common import Status
from py_trees.ports import PortInformation

from planner.composition import static_composition
from planner.held_states import measured_dual_state, on_measured_object
from planner.leaves.base import MotionLeaf
from planner.leaves.palm_motion import ViaPointLeaf, measured_state
from planner.leaves.palm_routes import PalmRoute, margin_port, take_clear_route
from planner.leaves.set_down import lowered, palm_load_n, supported_below_n
from planner.port import ArmJoints, Clock, ObjectSensing, ObstacleScene, PalmControl, Pose
from planner.skill_terms import opening_terms
from skills import quaternion as quat
from skills.composer import DualArmComposer, DualArmState, commands_for
from skills.dual_arm import GraspGeometry
from skills.state import PoseState
from skills.vocabulary import ARMS, Arm


def palms_facing(state: DualArmState) -> GraspGeometry:
    """The palms where they are in {O}, each pushing along its own contact normal (its frame's
    z axis): what opening moves them back along, whatever face of a turned box they press."""
    z = np.array([0.0, 0.0, 1.0])
    left, right = state.left, state.right
    return GraspGeometry(
        left.position.copy(),
        left.orientation.copy(),
        right.position.copy(),
        right.orientation.copy(),
        quat.rotate(left.orientation, z),
        quat.rotate(right.orientation, z),
    )


#: Further openings a release makes when the opened palms still touch the object.
MAX_REOPENINGS = 2


def held_at_rest(state: DualArmState) -> DualArmState:
    """``state``'s poses, everything at rest: a hold that does not move."""
    return DualArmState(
        *(
            PoseState.at_rest(p.position, p.orientation)
            for p in (state.object, state.left, state.right)
        )
    )


class Release(MotionLeaf):
    """Move each palm ``opening_m`` out along its contact normal (a relative skill), from where
    the palms and the object are as measured
    (:func:`~planner.held_states.measured_dual_state`): both let the squeeze off together.
    Opening from the commanded references, pressed into the faces, a palm that leaves first lets
    the other's squeeze push the object over (a slipped parcel squeezed at 100 N toppled so).

    An object the palms still carry (their upward force above
    :func:`~planner.leaves.set_down.supported_below_n`: no surface under it, as after a carry
    cut short by a slip) is first set down: both palms, holding the grip, lower it straight
    at ``set_down_speed_m_s`` until a surface takes it, searching at most ``set_down_m``
    below where it was held (else the release fails, saying so, and holds it there).
    Opening in the air would drop it, onto whatever stands below.
    """

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
        "set_down_m": PortInformation(
            float,
            required=False,
            default_value=0.15,
            description="how far below where it is held the palms search for a surface to "
            "set a carried object down on before opening, m (0: open where it is)",
        ),
        "set_down_speed_m_s": PortInformation(
            float,
            required=False,
            default_value=0.05,
            description="how fast the palms lower a carried object, m/s",
        ),
    }
    OUTPUT_PORTS = {
        "to_state": PortInformation(DualArmState, description="full state after opening"),
    }

    def initialise(self) -> None:
        """Set down an object the palms carry, else compose the opening at once."""
        self.composer: DualArmComposer | None = None
        self.lowering_from: float | None = None
        if self.connected() is not None:
            return
        world = self.world
        self.object_name = name = self.get_input("object")
        self.reopenings = 0
        state = self.get_input("from_state")
        self.supported_below_n = supported_below_n(world, name)
        self.set_down_m = float(self.get_input("set_down_m"))
        self.set_down_speed = float(self.get_input("set_down_speed_m_s"))
        # Open along the faces as the object stands (a box that lagged its palms in a turn is
        # not where the last move commanded it), unless it must be set down first; the
        # lowering keeps the palms' references, and so the squeeze, of the handed-over state.
        if self.set_down_m > 0.0 and palm_load_n(world, name) > self.supported_below_n:
            if self.set_down_speed <= 0.0:
                raise ValueError(
                    f"set_down_speed_m_s must be positive, got {self.set_down_speed:g}"
                )
            self.held = held_at_rest(on_measured_object(world, name, state))
            self.lowering_from = world.time()
            return
        self._open_from(measured_dual_state(world, name))

    def _open_from(self, state: DualArmState) -> None:
        relative = opening_terms(palms_facing(state), float(self.get_input("opening_m")))
        self.composer = static_composition(state, relative, float(self.get_input("open_s")))
        self.started = self.world.time()

    def _set_down(self) -> Status:
        """Lower the held object a control step; open once a surface carries it."""
        world, name = self.world, self.object_name
        assert self.lowering_from is not None
        depth = self.set_down_speed * (world.time() - self.lowering_from)
        load = palm_load_n(world, name)
        if load <= self.supported_below_n:
            self.lowering_from = None
            self._open_from(measured_dual_state(world, name))
            return self.running(f"set down {depth * 1000:.0f} mm lower; opening")
        if depth > self.set_down_m:
            return self.fail(
                f"no surface took the object within {self.set_down_m * 1000:.0f} mm below "
                f"where it was held (the palms still carry {load:.1f} N): not letting go"
            )
        cmd = commands_for(lowered(self.held, depth, self.set_down_speed))
        for i, arm in enumerate(ARMS):
            world.command_palm(arm, Pose(cmd.positions[i], cmd.orientations[i]), cmd.twists[i])
        return self.running(
            f"setting down before letting go: {depth * 1000:.0f} mm lower, "
            f"the palms carry {load:.1f} N"
        )

    def update(self) -> Status:
        """RUNNING while setting down and opening; SUCCESS when out of contact and still."""
        if (why := self.connected()) is not None:
            return self.fail(why)
        if self.lowering_from is not None:
            return self._set_down()
        assert self.composer is not None
        world = self.world
        cmd = self.composer.step(self.control_dt)
        for i, arm in enumerate(ARMS):
            world.command_palm(arm, Pose(cmd.positions[i], cmd.orientations[i]), cmd.twists[i])
        forces = [world.contact_force(arm, self.get_input("object")) for arm in ARMS]
        st = self.composer.state
        still = max(np.linalg.norm(st.left.velocity), np.linalg.norm(st.right.velocity)) < 5e-3
        settled = still and world.time() - self.started > 0.3
        if max(forces) < 0.5 and settled:
            self._set_output("to_state", st)
            return self.succeed("palms open and clear of the object")
        if settled and self.reopenings < MAX_REOPENINGS:
            # The palms stand open and still, yet one is pressed: the object leans on it or
            # came with it. Open again from here, along the faces as the object now stands.
            self.reopenings += 1
            self._open_from(on_measured_object(world, self.get_input("object"), st))
            return self.running(
                f"opening further ({self.reopenings} of {MAX_REOPENINGS}): the object "
                f"still presses {max(forces):.1f} N on a palm"
            )
        return self.running(f"opening: {forces[0]:.1f} N, {forces[1]:.1f} N")


#: How far a retreat that must keep low backs away at least, m.
LOW_BACK_M = 0.06


class Retreat(ViaPointLeaf):
    """Take both palms back to their rest poses, backing away and rising first.

    Before moving, the path is predicted and checked against the obstacles
    (:mod:`planner.leaves.palm_routes`); if it is not clear by ``margin_m``, the first clear of:
    backing further away and rising half as high, the usual way around the obstacle nearest its
    path, rising straight without backing away, or backing away and staying there.
    """

    WORLD_ROLES: ClassVar[tuple[type, ...]] = (PalmControl, ObstacleScene, ArmJoints)

    INPUT_PORTS = {
        "back_m": PortInformation(
            float,
            required=False,
            default_value=0.0,
            description="how far each palm first backs away from what it faced (along its "
            "contact normal), m: beside a turned object, rising straight up may drag it",
        ),
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
        "margin_m": margin_port(),
    }
    OUTPUT_PORTS: dict[str, PortInformation] = {}
    MOVING = "retreating"
    ARRIVED = "palms at rest"

    def initialise(self) -> None:
        """Plan rise-then-rest from where the palms are, by a way clear of the obstacles."""
        self.motion = None
        if self.connected() is not None:
            return
        world = self.world
        rise = float(self.get_input("rise_m"))
        back = float(self.get_input("back_m"))
        here = {arm: world.palm_pose(arm) for arm in ARMS}
        rest = {arm: world.rest_palm_pose(arm) for arm in ARMS}

        def backing(distance: float, height: float | None) -> dict[Arm, list[Pose]]:
            """Back ``distance`` along the normals, rise ``height`` and go to rest; or, for
            a height of None, stay backed away."""
            out = {}
            for arm in ARMS:
                pose = here[arm]
                # The palm frame's z is its contact normal, pointing out of its face.
                normal = quat.rotate(pose.orientation, np.array([0.0, 0.0, 1.0]))
                away = pose.position - distance * normal
                first = [Pose(away, pose.orientation)] if distance > 0.0 else []
                if height is None:
                    out[arm] = [Pose(away, pose.orientation)]
                    continue
                up = Pose(away + np.array([0.0, 0.0, height]), pose.orientation)
                out[arm] = [*first, up, rest[arm]]
            return out

        routes = [
            PalmRoute("backing away and rising", backing(back, rise)),
            PalmRoute(
                "backing further and rising less", backing(max(2 * back, LOW_BACK_M), rise / 2)
            ),
            # Backing along the normal can carry a forearm into an obstacle behind the palm.
            PalmRoute("rising straight", backing(0.0, rise)),
            PalmRoute("backing away and staying", backing(max(back, LOW_BACK_M / 2), None)),
        ]
        if back <= 0.0:
            del routes[2]  # the usual way already
        starts = {a: measured_state(here[a], world.palm_twist(a)) for a in ARMS}
        take_clear_route(
            self,
            world,
            starts,
            routes,
            float(self.get_input("segment_s")),
            float(self.get_input("margin_m")),
            detour_of=0,
            detour_at=2,
        )
