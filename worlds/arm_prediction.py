"""Where the arms' links go along predicted palm paths: inverse kinematics on a kinematic copy.

Path checks (:meth:`worlds.sim_world.SimWorld.check_trajectory`) predict the palms and the held
object by rolling the composition out; the links behind the palms follow from the joints.
Carried rigidly with the palms (:meth:`worlds.collision.CollisionWorld.check_attached_links`),
the links miss the elbow's swing over a carry, and on a robot whose arms share joints (the
iCub's torso) the torso's, which swings both arms while one palm carries the object sideways:
a forearm ends centimetres from where the rigid carry puts it. Here each waypoint's palm poses
are solved for every arm of a body at once (:func:`worlds.palm_ik.solve_palms`, warm-started
from the waypoint before, the first from the measured joints, with the controller's
null-space posture as the rest posture) on a copy of the robot in its own PyBullet client, so
the scene's physics is never touched, and the links' frames are read from it. Every robot's
path checks use it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pybullet as pb
from numpy.typing import NDArray

from skills.vocabulary import Arm
from worlds.bodies import load_robot
from worlds.palm_ik import solve_palms
from worlds.robots.model import BodySpec, RobotModel
from worlds.scene import Scene

FloatArray = NDArray[np.float64]

#: Most damped-least-squares steps per waypoint: each starts from the one before, a few
#: millimetres away, so it converges in a handful.
WAYPOINT_ITERATIONS = 10
#: Palm pose error at which a waypoint's solve stops, m and rad: a millimetre, a tenth of the
#: least margin the links are checked with. At 1e-4 a third of the solves took a second step
#: and a fifth ran to the cap; the IK's share of an episode fell from 12 to 9 % at 1e-3.
WAYPOINT_TOLERANCE = 1e-3


@dataclass(frozen=True)
class LinkFrames:
    """Link frames (PyBullet's centre-of-mass frames, as ``getLinkState``'s first two) of one
    arm along a path.

    Attributes
    ----------
    links : tuple of int
        (L,) link indices on the arm's body.
    positions : ndarray
        (N, L, 3) world frame, m.
    quaternions : ndarray
        (N, L, 4) scalar-last.
    """

    links: tuple[int, ...]
    positions: FloatArray
    quaternions: FloatArray


#: The kinematic copies loaded in this process, by the robot bodies they copy (URDF files and
#: base poses: all a copy's link frames depend on), each (client, body ids). A campaign's
#: worker loads its robot's copy once, not once a trial (1.2 % of a trial's time, profiled
#: over 8 trials). Sharing one is safe: every solve resets all the joints it moves first
#: (:func:`worlds.palm_ik.solve_palms`), so no prediction depends on the one before.
_COPIES: dict[tuple[BodySpec, ...], tuple[int, tuple[int, ...]]] = {}


def _kinematic_copy(robot: RobotModel) -> tuple[int, tuple[int, ...]]:
    """This process's copy of ``robot``'s bodies in a client of its own: (client, body ids)."""
    key = tuple(robot.bodies)
    copy = _COPIES.get(key)
    if copy is None or not pb.isConnected(physicsClientId=copy[0]):
        client = pb.connect(pb.DIRECT)
        copy = _COPIES[key] = (client, load_robot(client, robot))
    return copy


class ArmPredictor:
    """A kinematic copy of ``scene``'s robot that answers where its links go.

    Parameters
    ----------
    scene : Scene
        The running scene: its joints are read at each prediction. The copy of its robot is
        the process's (:func:`_kinematic_copy`), loaded by the first predictor of that robot.
    """

    def __init__(self, scene: Scene) -> None:
        self._scene = scene
        self._client, self._ids = _kinematic_copy(scene.robot)
        # Per arm of the last link_frames: (copy body, palm link, the path's last palm target).
        self._last_targets: list[tuple[Arm, int, int, FloatArray]] = []

    def close(self) -> None:
        """Let go of the copy (idempotent); it stays loaded for the next predictor."""
        self._client = -1

    def link_frames(
        self,
        palm_positions: FloatArray,
        palm_quaternions: FloatArray,
        links: dict[Arm, tuple[int, ...]],
        iterations: int = WAYPOINT_ITERATIONS,
        tolerance: float = WAYPOINT_TOLERANCE,
    ) -> dict[Arm, LinkFrames]:
        """Each arm's ``links`` along the palm path.

        Parameters
        ----------
        palm_positions : ndarray
            (N, 2, 3) left and right palm positions, world frame, m.
        palm_quaternions : ndarray
            (N, 2, 4) their orientations, scalar-last.
        links : dict of Arm to tuple of int
            Per arm, the link indices on its body to report.
        iterations, tolerance : int, float
            Each waypoint's solve: most steps, and the pose error it stops at (m, rad). The
            defaults follow a path of nearby waypoints; a lone pose far from the measured
            joints needs a solve run to convergence (a few hundred steps).

        Returns
        -------
        dict of Arm to LinkFrames
        """
        scene, robot = self._scene, self._scene.robot
        positions = np.asarray(palm_positions, dtype=float)
        quaternions = np.asarray(palm_quaternions, dtype=float)
        n = positions.shape[0]
        driven = robot.driven_joints()
        rest_all = scene.controller.rest_posture()
        out: dict[Arm, LinkFrames] = {}
        self._last_targets = []
        for index in dict.fromkeys(robot.arms[a].body for a in (Arm.LEFT, Arm.RIGHT)):
            arms = [a for a in (Arm.LEFT, Arm.RIGHT) if robot.arms[a].body == index]
            rows = [k for k, d in enumerate(driven) if d.body == index]
            joints = [driven[k].joint for k in rows]
            lower = np.array([driven[k].lower for k in rows])
            upper = np.array([driven[k].upper for k in rows])
            rest = rest_all[rows]
            cost = np.array([robot.ik_cost(driven[k]) for k in rows])
            states = pb.getJointStates(scene.robot_ids[index], joints, physicsClientId=scene.client)
            q = np.array([s[0] for s in states])
            copy = self._ids[index]
            palm_links = [robot.arms[a].palm_link for a in arms]
            arm_index = [0 if a is Arm.LEFT else 1 for a in arms]
            frames = {
                a: (np.zeros((n, len(links[a]), 3)), np.zeros((n, len(links[a]), 4))) for a in arms
            }
            for w in range(n):
                targets = [(positions[w, i], quaternions[w, i]) for i in arm_index]
                q = solve_palms(
                    self._client,
                    copy,
                    joints,
                    palm_links,
                    targets,
                    q,
                    lower,
                    upper,
                    rest,
                    cost,
                    iterations=iterations,
                    tolerance=tolerance,
                )
                for a in arms:
                    if not links[a]:
                        continue
                    read = pb.getLinkStates(
                        copy,
                        list(links[a]),
                        computeForwardKinematics=1,
                        physicsClientId=self._client,
                    )
                    frames[a][0][w] = [s[0] for s in read]
                    frames[a][1][w] = [s[1] for s in read]
            for a in arms:
                out[a] = LinkFrames(tuple(links[a]), frames[a][0], frames[a][1])
            if n:
                self._last_targets += [
                    (a, copy, link, positions[-1, i])
                    for a, i, link in zip(arms, arm_index, palm_links, strict=True)
                ]
        return out

    def last_palm_errors(self) -> dict[Arm, float]:
        """Per arm, how far (m) the last :meth:`link_frames` left its palm from the path's last
        waypoint, read off the copy, which stands at that solution until the next solve: over
        a few millimetres, the solve did not reach it (out of reach, or too few iterations)."""
        errors = {}
        for arm, body, link, target in self._last_targets:
            at = pb.getLinkState(
                body, link, computeForwardKinematics=1, physicsClientId=self._client
            )
            errors[arm] = float(np.linalg.norm(np.subtract(at[4], target)))
        return errors


__all__ = ["WAYPOINT_ITERATIONS", "WAYPOINT_TOLERANCE", "ArmPredictor", "LinkFrames"]
