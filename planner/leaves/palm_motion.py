"""Free palm motions (before grasping and after releasing): DMPs through via-points.

Each palm runs its own pose DMP in the world frame; at a via-point the next segment starts
from the full state of the previous one (pose, velocity, acceleration), so the palm sweeps
through without stopping or jumping.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any, ClassVar

import numpy as np
from py_trees.common import Status

from planner.leaves.base import MotionLeaf
from planner.port import Pose
from skills import quaternion as quat
from skills.pose_dmp import PoseDMP, PoseModel, PoseState
from skills.vocabulary import Arm


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


class ViaPointLeaf(MotionLeaf):
    """A leaf that moves both palms through via-points: subclasses plan ``self.motion``.

    ``initialise()`` builds a :class:`ViaPointMotion`; ``update()`` (here) commands one step
    of it per tick and succeeds when both palms are at their last pose.
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
    #: 699 of the default world's 1000-trial record). In 2 of 300 Hard trials (121, 196) a
    #: step back's palm stopped 12-13 cm short, and the tree went on another way to succeed.
    ARRIVAL_M: ClassVar[float] = 0.08

    def __init__(self, name: str, **kwargs: Any) -> None:
        super().__init__(name=name, **kwargs)
        self.motion: ViaPointMotion | None = None
        #: Which way the palms take, when not the usual one (added to the feedback).
        self.route_note = ""
        #: Why ``initialise()`` planned no motion (the leaf then fails at once), or None.
        self.refusal: str | None = None

    def update(self) -> Status:
        """Command one step of the motion; SUCCESS at the last via-point."""
        if (why := self.connected()) is not None:
            return self.fail(why)
        if self.refusal is not None:
            return self.fail(self.refusal)
        assert self.motion is not None
        for arm, st in self.motion.step(self.control_dt).items():
            self.world.command_palm(arm, Pose(st.position, st.orientation), st.twist())
        note = f" ({self.route_note})" if self.route_note else ""
        if self.motion.done():
            if (short := self.short_of_arrival()) is not None:
                return self.fail(short + note)
            return self.succeed(self.ARRIVED + note)
        return self.running(f"{self.MOVING}: {self.motion.remaining():.3f} m to go{note}")

    def short_of_arrival(self) -> str | None:
        """Why the palms are not where the arrived motion left them (a palm measured more
        than :attr:`ARRIVAL_M` from its last pose), or None."""
        assert self.motion is not None
        for arm, waypoints in self.motion.waypoints.items():
            gap = float(np.linalg.norm(self.world.palm_pose(arm).position - waypoints[-1].position))
            if gap > self.ARRIVAL_M:
                return (
                    f"the {arm.value} palm stopped {gap * 1000:.0f} mm from its pose (more than "
                    f"{self.ARRIVAL_M * 1000:.0f} mm): its arm did not follow the motion "
                    "(held against something, or a joint at its limit)"
                )
        return None
