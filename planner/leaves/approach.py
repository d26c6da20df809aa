"""Approach: bring both palms beside the object's faces through middle set-points."""

from __future__ import annotations

from typing import ClassVar

import numpy as np
from py_trees.ports import PortInformation

from planner.grips import grasp_options, lateral_geometry, move_turn, robot_yaw
from planner.leaves.base import grasp_move_port
from planner.leaves.palm_motion import ViaPointLeaf, ViaPointMotion, measured_state
from planner.leaves.palm_routes import PalmRoute, margin_port, take_clear_route
from planner.port import ArmJoints, ObjectSensing, ObstacleScene, PalmControl, Pose, WorldPort
from skills import quaternion as quat
from skills.flip import vertical_half_extent
from skills.pose_dmp import PoseState
from skills.turns import grip_yaw, wrap_angle, yaw_of
from skills.vocabulary import ARMS, Arm


def pregrasp_poses(
    object_pose: Pose,
    geometry_positions: dict[Arm, np.ndarray],
    geometry_orientations: dict[Arm, np.ndarray],
    normals: dict[Arm, np.ndarray],
    standoff: float,
    rise: float,
) -> dict[Arm, list[Pose]]:
    """Middle set-point (outside and above) then the pre-grasp pose, per palm, world frame."""
    out: dict[Arm, list[Pose]] = {}
    for arm in ARMS:
        outward = -normals[arm]
        rel_pre = geometry_positions[arm] + standoff * outward
        rel_mid = geometry_positions[arm] + 2.0 * standoff * outward
        q = quat.multiply(object_pose.orientation, geometry_orientations[arm])
        pre = object_pose.position + quat.rotate(object_pose.orientation, rel_pre)
        mid = object_pose.position + quat.rotate(object_pose.orientation, rel_mid)
        mid = mid + np.array([0.0, 0.0, rise])
        out[arm] = [Pose(mid, q), Pose(pre, q)]
    return out


#: Turned this far from the palms' natural grip, an object's corners stand in the palms' way.
TURNED_RAD = np.radians(15.0)


def clear_rise(world: WorldPort, name: str, pose: Pose, quarter_turns: int, rise: float) -> float:
    """Height of the middle set-points above the grasp: ``rise``, or, when the object stands
    turned from the palms' natural grip (a re-grasp after a turn), enough for the palms to
    pass above its top (a straight way in from the side would sweep its corners)."""
    grip = wrap_angle(grip_yaw(yaw_of(pose.orientation), quarter_turns, robot_yaw(world)))
    if abs(grip) <= TURNED_RAD:
        return rise
    return above_rise(world, name, rise)


def above_rise(world: WorldPort, name: str, rise: float) -> float:
    """Height of middle set-points that take the palms in above the object's top."""
    top = float(world.object_extents(name)[2]) / 2.0  # the grasp is at the centre's height
    # A palm's farthest point from its centre, across its face.
    palm_reach = float(max(world.robot_capabilities().palm_size_m[:2])) / 2.0
    return max(rise, top + palm_reach + 0.02)


#: How far a resting object may lie below the table top, or beyond its edge, before it is
#: taken to have fallen off, m: beyond the table's uncertain height (Hard mode's +-3 cm).
OFF_TABLE_M = 0.05


def off_the_table(world: WorldPort, name: str) -> str | None:
    """Why the object cannot be grasped where it lies, off the table (its lowest point more
    than :data:`OFF_TABLE_M` below the table top, or its centre that far beyond the table's
    edge), or None."""
    pose = world.object_pose(name)
    extents = world.object_extents(name)
    lower, upper = world.workspace_bounds(name)
    top = float(lower[2] - extents[2] / 2.0)
    below = top - float(pose.position[2] - vertical_half_extent(extents, pose.orientation))
    beyond = float(np.max(np.maximum(lower[:2] - pose.position[:2], pose.position[:2] - upper[:2])))
    if below <= OFF_TABLE_M and beyond <= OFF_TABLE_M:
        return None
    where = ", ".join(f"{v:.2f}" for v in pose.position)
    if beyond <= OFF_TABLE_M and below < 0.5 * top:
        # Over the table, lower than its top but far above the floor: a table lower than the
        # world states (Hard mode's table_dz_m, a world file's error), or the object under it.
        return (
            f"{name} lies {below:.2f} m below the table top the world states, over the table: "
            f"the table is lower than stated (or the object beneath it); out of reach: at "
            f"({where}) m"
        )
    if below > OFF_TABLE_M:
        side = f"{below:.2f} m below the table top"
    else:
        side = f"{beyond:.2f} m beyond the table's edge"
    return f"{name} lies off the table, out of reach: at ({where}) m, {side}"


#: A palm that starts this far below its middle set-point rises before heading for it, on the
#: "rising first" routes, m.
RISE_FIRST_M = 0.01


def rising_first(routes: list[PalmRoute], starts: dict[Arm, PoseState]) -> list[PalmRoute]:
    """Each route with a first set-point straight above where each palm starts, at its middle
    set-point's height, for palms that start low beside the object (stepped back from it after
    letting it go): heading straight for a middle set-point over another face, their way
    cuts through the object's corner. Empty when no palm starts that low."""
    out = []
    for route in routes:
        low = [
            a
            for a in ARMS
            if route.waypoints[a][0].position[2] - starts[a].position[2] > RISE_FIRST_M
        ]
        if not low:
            continue
        waypoints = {}
        for a in ARMS:
            points = list(route.waypoints[a])
            if a in low:
                above = np.array(starts[a].position, dtype=float)
                above[2] = points[0].position[2]
                points.insert(0, Pose(above, np.asarray(starts[a].orientation, dtype=float)))
            waypoints[a] = points
        out.append(PalmRoute(f"rising first, then {route.name}", waypoints))
    return out


class Approach(ViaPointLeaf):
    """Move both palms to ``standoff`` m outside the object's faces via set-points above.

    The faces are the pair that suits move ``move``'s turn (:mod:`skills.turns`), from the
    object's measured yaw: after a turn, the palms meet the faces that now face them. When every
    way in to that pair ends with a palm or an arm link on an obstacle (a box set down turned
    beside a sphere, an arm reaching round its far face into it), the other pairs that make the
    turn are tried (:func:`~planner.grips.grasp_options`) and the first with a way in is
    taken; ``Grasp`` closes on the faces the palms come to.

    An object that lies off the table (:func:`off_the_table`: fallen to the floor) is out of
    reach: the leaf fails at once, saying where it lies.

    Before moving, the path is predicted and checked against the obstacles
    (:mod:`planner.leaves.palm_routes`); if it is not clear by ``margin_m``, the first clear of:
    the other way in (from above the object's top instead of from the side, or the reverse),
    each of those rising first when the palms start low beside the object
    (:func:`rising_first`), or the usual way around the obstacle, or other object, nearest its
    path. The check keeps the palms off the objects where they lie by ``object_margin_m``: a
    way in comes near its object, so by default it asks only that they do not touch (asked
    the 1 cm margin, ways in that passed 5 mm from the object's corner were refused, and the
    palms took ways that left them unable to grasp: trials 655, 699 and 799 of the default
    world's 1000).
    """

    WORLD_ROLES: ClassVar[tuple[type, ...]] = (ObjectSensing, PalmControl, ObstacleScene, ArmJoints)

    INPUT_PORTS = {
        "object": PortInformation(str, description="object to approach"),
        "move": grasp_move_port(),
        "standoff_m": PortInformation(
            float,
            required=False,
            default_value=0.04,
            description="gap between palm and face at the end, m",
        ),
        "rise_m": PortInformation(
            float,
            required=False,
            default_value=0.08,
            description="height of the middle set-point above, m",
        ),
        "segment_s": PortInformation(
            float,
            required=False,
            default_value=1.5,
            description="duration scale of each segment, s",
        ),
        "margin_m": margin_port(),
        "object_margin_m": PortInformation(
            float,
            required=False,
            default_value=0.0,
            description="clearance from the objects where they rest the palms' predicted "
            "path must keep, m (0: not touching them; a way in comes near its object)",
        ),
    }
    OUTPUT_PORTS: dict[str, PortInformation] = {}
    MOVING = "approaching"
    ARRIVED = "palms at the pre-grasp poses"

    def initialise(self) -> None:
        """Plan the via-point motion from where the palms are now, by a way clear of the
        obstacles."""
        self.motion = None
        self.refusal = None
        if self.connected() is not None:
            return
        world = self.world
        name = self.get_input("object")
        if (why := off_the_table(world, name)) is not None:
            self.refusal = why
            return
        turn = move_turn(world, name, int(self.get_input("move")))
        starts = {a: measured_state(world.palm_pose(a), world.palm_twist(a)) for a in ARMS}
        options = grasp_options(world, name, turn)
        first: tuple[ViaPointMotion | None, str | None, str] | None = None
        for k in options:
            take_clear_route(
                self,
                world,
                starts,
                self._routes(world, name, k, starts),
                float(self.get_input("segment_s")),
                float(self.get_input("margin_m")),
                detour_of=0,
                around=world.other_objects(name),
                object_margin_m=float(self.get_input("object_margin_m")),
            )
            if self.refusal is None:
                if first is not None:
                    self.route_note = f"on the other faces that make the turn: {first[1]}" + (
                        f"; {self.route_note}" if self.route_note else ""
                    )
                return
            if first is None:
                first = (self.motion, self.refusal, self.route_note)
        # Every pair of faces refused: the usual pair's reason.
        assert first is not None
        self.motion, self.refusal, self.route_note = first

    def _routes(
        self, world: WorldPort, name: str, quarter_turns: int, starts: dict[Arm, PoseState]
    ) -> list[PalmRoute]:
        """The ways in to face pair ``quarter_turns``: the usual, the other (from above or from
        the side), and each of them rising first where the palms start low."""
        g = lateral_geometry(world, name, quarter_turns)
        pose = world.object_pose(name)
        rise_m = float(self.get_input("rise_m"))
        rise = clear_rise(world, name, pose, quarter_turns, rise_m)

        def way_in(height: float) -> dict[Arm, list[Pose]]:
            return pregrasp_poses(
                pose,
                {a: g.position(a) for a in ARMS},
                {a: g.orientation(a) for a in ARMS},
                {a: g.normal(a) for a in ARMS},
                float(self.get_input("standoff_m")),
                height,
            )

        usual = "from above" if rise > rise_m else "from the side"
        other, other_rise = (
            ("from the side", rise_m)
            if rise > rise_m
            else ("from above", above_rise(world, name, rise_m))
        )
        routes = [PalmRoute(f"coming in {usual}", way_in(rise))]
        if other_rise != rise:
            routes.append(PalmRoute(f"coming in {other}", way_in(other_rise)))
        routes.extend(rising_first(routes, starts))
        return routes
