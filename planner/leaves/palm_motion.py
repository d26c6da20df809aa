"""Free palm motions (before grasping and after releasing): DMPs through via-points.

Each palm runs its own pose DMP in the world frame; at a via-point the next segment starts
from the full state of the previous one (pose, velocity, acceleration), so the palm sweeps
through without stopping or jumping.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any, ClassVar, cast

import numpy as np
from py_trees.common import Status

from planner.leaves.base import MotionLeaf
from planner.port import ArmJoints, ObstacleScene, Pose, offers
from skills import quaternion as quat
from skills.pose_dmp import PoseDMP, PoseModel, PoseState
from skills.types import Array
from skills.vocabulary import ARMS, Arm


class ViaPointMotion:
    """Both palms through their via-points, one pose DMP segment each.

    Parameters
    ----------
    starts : mapping Arm -> PoseState
        Where each palm starts (its measured pose, at rest or moving).
    waypoints : mapping Arm -> sequence of Pose
        Via-points then the final pose, world frame.
    segment_tau : float
        Duration scale of each segment, s.
    switch_at : float
        Fraction of a segment's ``tau`` after which the next segment takes over.
    model : PoseModel, optional
        A learnt free-motion skill; the default is a plain critically damped DMP.
    """

    def __init__(
        self,
        starts: Mapping[Arm, PoseState],
        waypoints: Mapping[Arm, Sequence[Pose]],
        segment_tau: float,
        switch_at: float = 0.6,
        model: PoseModel | None = None,
    ) -> None:
        if segment_tau <= 0:
            raise ValueError(f"segment_tau: expected a positive duration in s, got {segment_tau}")
        self.model = model or PoseModel.still()
        self.waypoints = {arm: list(w) for arm, w in waypoints.items()}
        self.segment_tau = segment_tau
        self.switch_at = switch_at
        self.index = {arm: 0 for arm in self.waypoints}
        self.elapsed = 0.0
        self.dmps = {
            arm: PoseDMP.start(
                self.model, starts[arm], w[0].position, w[0].orientation, segment_tau
            )
            for arm, w in self.waypoints.items()
        }

    def step(self, dt: float) -> dict[Arm, PoseState]:
        """Advance every palm by ``dt``; switch segments at their via-points."""
        self.elapsed += dt
        switch = self.elapsed >= self.switch_at * self.segment_tau
        out = {}
        for arm, dmp in self.dmps.items():
            if switch and self.index[arm] < len(self.waypoints[arm]) - 1:
                self.index[arm] += 1
                goal = self.waypoints[arm][self.index[arm]]
                dmp = PoseDMP.start(
                    self.model, dmp.state, goal.position, goal.orientation, self.segment_tau
                )
                self.dmps[arm] = dmp
            out[arm] = dmp.step(dt)
        if switch:
            self.elapsed = 0.0
        return out

    def remaining(self) -> float:
        """Largest distance of any palm's reference to its final pose, m."""
        return max(
            float(np.linalg.norm(d.state.position - self.waypoints[a][-1].position))
            for a, d in self.dmps.items()
        )

    def done(self, tol_m: float = 2e-3, tol_speed: float = 5e-3) -> bool:
        """All palms on their last segment, near its pose and nearly still."""
        for arm, dmp in self.dmps.items():
            if self.index[arm] < len(self.waypoints[arm]) - 1:
                return False
            goal = self.waypoints[arm][-1]
            if np.linalg.norm(dmp.state.position - goal.position) > tol_m:
                return False
            if np.linalg.norm(dmp.state.velocity) > tol_speed:
                return False
            if quat.angle_between(dmp.state.orientation, goal.orientation) > 10 * tol_m:
                return False
        return True


def at_rest(pose: Pose) -> PoseState:
    """A palm state at ``pose`` with zero velocity."""
    return PoseState.at_rest(pose.position, pose.orientation)


def measured_state(pose: Pose, twist: np.ndarray) -> PoseState:
    """A palm state from a measured pose and twist (accelerations unknown: zero)."""
    z = np.zeros(3)
    return PoseState(
        pose.position.copy(),
        twist[:3].copy(),
        z,
        pose.orientation.copy(),
        twist[3:].copy(),
        z.copy(),
        1.0,
    )


@dataclass(frozen=True)
class PalmPath:
    """A route's predicted palm path, one row per control step from the start.

    Attributes
    ----------
    positions : ndarray, shape (N, 2, 3)
        Left and right palm positions, world frame, m.
    orientations : ndarray, shape (N, 2, 4)
        Their orientations, scalar-last.
    segments : ndarray, shape (N, 2)
        Index of the via-point each palm heads for at each step.
    """

    positions: Array
    orientations: Array
    segments: Array


def predict_palm_path(
    starts: Mapping[Arm, PoseState],
    waypoints: Mapping[Arm, Sequence[Pose]],
    segment_tau: float,
    dt: float,
) -> PalmPath:
    """Roll out the via-point motion the leaf would run, open loop, until it ends.

    Parameters
    ----------
    starts : mapping Arm -> PoseState
        Where each palm starts.
    waypoints : mapping Arm -> sequence of Pose
        Via-points then the final pose, world frame.
    segment_tau : float
        Duration scale of each segment, s.
    dt : float
        Control step, s.
    """
    motion = ViaPointMotion(starts, waypoints, segment_tau)
    most = max(len(w) for w in waypoints.values())
    # Every segment but the last hands over at ``switch_at``; the last converges in a few tau.
    n_max = int(np.ceil((most * motion.switch_at + 4.0) * segment_tau / dt))
    positions = [np.stack([starts[a].position for a in ARMS])]
    orientations = [np.stack([starts[a].orientation for a in ARMS])]
    segments = [np.zeros(2, dtype=int)]
    for _ in range(n_max):
        states = motion.step(dt)
        positions.append(np.stack([states[a].position for a in ARMS]))
        orientations.append(np.stack([states[a].orientation for a in ARMS]))
        segments.append(np.array([motion.index[a] for a in ARMS]))
        if motion.done():
            break
    return PalmPath(np.array(positions), np.array(orientations), np.array(segments))


class ViaPointLeaf(MotionLeaf):
    """A leaf that moves both palms through via-points: subclasses plan ``self.motion``.

    ``initialise()`` builds a :class:`ViaPointMotion`; ``update()`` (here) commands one step
    of it per tick and succeeds when both palms are at their last pose. A palm still more
    than :attr:`ARRIVAL_M` from it when the motion has arrived is an arm the palm law could
    not move: where the world offers :class:`planner.port.ArmJoints`, that arm goes home in
    joint space (:class:`ArmsHome`) and from there to the last pose, once, before the leaf
    fails.
    """

    #: What the feedback says while moving and when done.
    MOVING = "moving"
    ARRIVED = "palms at their poses"
    #: Farthest a palm may be measured from its last pose when its motion has arrived there,
    #: m: beyond it the arm did not follow the motion, and the leaf fails saying so instead
    #: of reporting palms where they are not. Over default and Hard trials of the iiwas and
    #: the iCub the palms arrived within 3 mm to 29 mm (Hard mode's biased, lagging
    #: actuators); an iiwa arm whose elbow had reached its joint limit with the wrist on the
    #: table stopped 15-29 cm short of every way in and out it was sent on (trials 516 and
    #: 699 of the default world's 1000-trial record; freed in joint space, both succeed).
    #: In 2 of 300 Hard trials (121, 196) a step back's palm stopped 12-13 cm short.
    ARRIVAL_M: ClassVar[float] = 0.08
    #: How near its last pose a palm freed and taken home must be for the leaf to end there
    #: (a retreat's rest poses), m; farther, it plans the last stretch there (checked clear).
    SETTLED_M: ClassVar[float] = 0.01

    def __init__(self, name: str, **kwargs: Any) -> None:
        super().__init__(name=name, **kwargs)
        self.motion: ViaPointMotion | None = None
        #: Which way the palms take, when not the usual one (added to the feedback).
        self.route_note = ""
        #: Why ``initialise()`` planned no motion (the leaf then fails at once), or None.
        self.refusal: str | None = None
        #: The arms being taken home in joint space now (:class:`ArmsHome`), or None.
        self.freeing: ArmsHome | None = None

    def terminate(self, new_status: Status) -> None:
        """Forget this run's freeing of the arms; an arm still held in joint space (the leaf
        halted or failing on the way home) is given back to the palm law where it is, not sent
        back to the pose it could not reach."""
        if self.freeing is not None and not self.freeing.arrived() and self._world is not None:
            for arm in self.freeing.starts:
                self._world.command_palm(arm, self._world.palm_pose(arm))
        self.freeing = None
        super().terminate(new_status)

    def update(self) -> Status:
        """Command one step of the motion; SUCCESS at the last via-point."""
        if (why := self.connected()) is not None:
            return self.fail(why)
        if self.refusal is not None:
            return self.fail(self.refusal)
        assert self.motion is not None
        if self.freeing is not None and not self.freeing.arrived():
            return self._free_arms()
        for arm, st in self.motion.step(self.control_dt).items():
            self.world.command_palm(arm, Pose(st.position, st.orientation), st.twist())
        note = f" ({self.route_note})" if self.route_note else ""
        if self.motion.done():
            short = self.short_arms()
            if not short:
                return self.succeed(self.ARRIVED + note)
            if self.freeing is None and offers(self.world, ArmJoints):
                # Last resort before failing: the stuck arms home in joint space, and from
                # there to the motion's last poses.
                self.freeing = ArmsHome.of(cast(ArmJoints, self.world), tuple(short))
                self.route_note = f"{self.route_note}; " if self.route_note else ""
                self.route_note += f"{_arms(tuple(short))} freed"
                return self._free_arms()
            return self.fail(_stopped_short(short, self.ARRIVAL_M) + note)
        return self.running(f"{self.MOVING}: {self.motion.remaining():.3f} m to go{note}")

    def _free_arms(self) -> Status:
        """Take the stuck arms one step nearer home in joint space; once there, give them back
        to the palm law and go on from where the palms are to the motion's last poses (at
        once where they are there already, a retreat's rest poses)."""
        assert self.freeing is not None and self.motion is not None
        joints = cast(ArmJoints, self.world)
        for arm, q in self.freeing.step(self.control_dt).items():
            joints.command_joints(arm, q)
        if not self.freeing.arrived():
            return self.running(f"{self.MOVING}: {self.route_note}, going home in joint space")
        palms = self.world
        here = {arm: palms.palm_pose(arm) for arm in self.motion.waypoints}
        last = {arm: w[-1] for arm, w in self.motion.waypoints.items()}
        if all(_gap(here[a], last[a]) <= self.SETTLED_M for a in last):
            for arm, pose in last.items():
                palms.command_palm(arm, pose)
            return self.succeed(f"{self.ARRIVED} ({self.route_note})")
        for arm in self.freeing.starts:
            palms.command_palm(arm, here[arm])
        starts = {arm: measured_state(pose, palms.palm_twist(arm)) for arm, pose in here.items()}
        waypoints = {arm: [pose] for arm, pose in last.items()}
        tau = self.motion.segment_tau
        if offers(palms, ObstacleScene):
            path = predict_palm_path(starts, waypoints, tau, self.control_dt)
            check = cast(ObstacleScene, palms).check_palm_path(
                path.positions, path.orientations, self._margin_m()
            )
            if not check.clear:
                return self.fail(
                    f"{_arms(tuple(self.freeing.starts))} freed and home, but the way from "
                    f"there to the last poses is not clear: {check.detail}"
                )
        self.motion = ViaPointMotion(
            starts, waypoints, tau, self.motion.switch_at, self.motion.model
        )
        return self.running(f"{self.MOVING}: {self.route_note}, from home")

    def _margin_m(self) -> float:
        """The clearance the leaf's ways keep (its ``margin_m`` port; 0 without one), m."""
        return float(self.get_input("margin_m")) if "margin_m" in self.INPUT_PORTS else 0.0

    def short_arms(self) -> dict[Arm, float]:
        """The palms measured more than :attr:`ARRIVAL_M` from their last poses, with how
        far, m (empty when the arms followed the motion)."""
        assert self.motion is not None
        out = {}
        for arm, waypoints in self.motion.waypoints.items():
            gap = _gap(self.world.palm_pose(arm), waypoints[-1])
            if gap > self.ARRIVAL_M:
                out[arm] = gap
        return out


def _gap(a: Pose, b: Pose) -> float:
    return float(np.linalg.norm(a.position - b.position))


def _arms(arms: Sequence[Arm]) -> str:
    """ "the left arm", "the left and right arms"."""
    return f"{' and '.join(a.value for a in arms)} arm{'s' if len(arms) > 1 else ''}"


def _stopped_short(short: Mapping[Arm, float], limit_m: float) -> str:
    """Why the leaf fails: each palm short of its last pose and by how much."""
    palms = " and ".join(
        f"the {arm.value} palm{' stopped' if k == 0 else ''} {gap * 1000:.0f} mm"
        for k, (arm, gap) in enumerate(short.items())
    )
    return (
        f"{palms} from {'their poses' if len(short) > 1 else 'its pose'} (more than "
        f"{limit_m * 1000:.0f} mm): {'their arms' if len(short) > 1 else 'its arm'} did not "
        "follow the motion (held against something, or a joint at its limit)"
    )


class ArmsHome:
    """Arms going from where their joints are to their rest postures in joint space, on a
    minimum-jerk path, then holding still there :attr:`SETTLE_S`.

    Parameters
    ----------
    starts, homes : mapping Arm -> ndarray
        Joint positions now and at rest, rad.
    """

    #: Mean joint speed of the way home, rad/s, the farthest joint setting the duration: its
    #: peak, 1.875 times it (minimum jerk), is 1.31 rad/s, the slowest iiwa 14 joint's
    #: 75 deg/s (A4; the others 85-135).
    SPEED = 0.7
    #: Shortest way home, s.
    LEAST_S = 0.8
    #: Longest way home, s: the shipped trees' 6 s guards around a step back (about 2.2 s)
    #: leave room for it and :attr:`SETTLE_S`. A joint farther than ``SPEED * LONGEST_S``
    #: from rest goes faster than :attr:`SPEED`.
    LONGEST_S = 3.0
    #: Time held at home before the palm law takes over again, s.
    SETTLE_S = 0.25

    def __init__(self, starts: Mapping[Arm, np.ndarray], homes: Mapping[Arm, np.ndarray]) -> None:
        self.starts = {arm: np.asarray(q, dtype=float) for arm, q in starts.items()}
        self.homes = {arm: np.asarray(homes[arm], dtype=float) for arm in starts}
        farthest = max(float(np.max(np.abs(self.homes[a] - q))) for a, q in self.starts.items())
        self.duration = min(max(self.LEAST_S, farthest / self.SPEED), self.LONGEST_S)
        self.elapsed = 0.0

    @classmethod
    def of(cls, world: ArmJoints, arms: Sequence[Arm]) -> ArmsHome:
        """``arms`` of ``world`` from their measured joints to their rest postures."""
        return cls(
            {arm: world.arm_joints(arm) for arm in arms},
            {arm: world.rest_joints(arm) for arm in arms},
        )

    def step(self, dt: float) -> dict[Arm, np.ndarray]:
        """Advance ``dt``: each arm's joint targets, rad."""
        self.elapsed += dt
        u = min(1.0, self.elapsed / self.duration)
        s = u * u * u * (10.0 - 15.0 * u + 6.0 * u * u)
        return {arm: q + s * (self.homes[arm] - q) for arm, q in self.starts.items()}

    def arrived(self) -> bool:
        """Home and held there :attr:`SETTLE_S`."""
        return self.elapsed >= self.duration + self.SETTLE_S - 1e-9
