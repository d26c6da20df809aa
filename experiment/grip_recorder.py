"""The samples of the grip metrics, read from the simulation once per control step.

:class:`GripRecorder` is the stateful half of :mod:`experiment.metrics`: the episode's
recorder calls :meth:`GripRecorder.sample` after every tick (it only reads: poses, twists,
contact forces), and :meth:`GripRecorder.metrics` stacks the rows and hands them to the pure
functions once, at the end of the run.
"""

from __future__ import annotations

import numpy as np

from experiment.metrics import GripMetrics, GripSamples, grip_metrics, worst
from planner.port import Pose
from skills.vocabulary import ARMS
from worlds.sim_world import SimWorld


class GripRecorder:
    """Per control step, each object's pose, twist and palm forces and both palms' positions
    and linear velocities, world frame.

    Parameters
    ----------
    sim : SimWorld
    control_dt : float
        Time between samples, s.
    """

    def __init__(self, sim: SimWorld, control_dt: float) -> None:
        self.sim = sim
        self.control_dt = control_dt
        self.objects = tuple(o.name for o in sim.spec.scene.objects)
        #: Per tick, (2, 6): each palm's position, m, and linear velocity, m/s.
        self.palm_rows: list[np.ndarray] = []
        #: Per object, per tick, (15,): position (3) m, quaternion (4), linear (3) m/s and
        #: angular (3) rad/s velocity, left and right palm normal forces (2) N.
        self.object_rows: dict[str, list[np.ndarray]] = {name: [] for name in self.objects}

    def sample(self) -> dict[str, Pose]:
        """Append this control step's rows; the object poses read, by name."""
        sim = self.sim
        # One link read per palm: its position and linear velocity.
        self.palm_rows.append(
            np.array([np.concatenate(sim.scene.palm_motion(arm)) for arm in ARMS])
        )
        poses = {}
        for name in self.objects:
            pose = poses[name] = sim.object_pose(name)
            forces = [sim.contact_force(arm, name) for arm in ARMS]
            self.object_rows[name].append(
                np.concatenate((pose.position, pose.orientation, sim.object_twist(name), forces))
            )
        return poses

    def samples(self, name: str) -> GripSamples:
        """Everything sampled of object ``name`` and the palms."""
        palms = np.array(self.palm_rows, dtype=float).reshape(-1, 2, 6)
        rows = np.array(self.object_rows[name], dtype=float).reshape(-1, 15)
        return GripSamples(
            object_positions=rows[:, 0:3],
            object_orientations=rows[:, 3:7],
            object_velocities=rows[:, 7:10],
            object_angular_velocities=rows[:, 10:13],
            palm_positions=palms[:, :, 0:3],
            palm_velocities=palms[:, :, 3:6],
            palm_forces=rows[:, 13:15],
            dt=self.control_dt,
        )

    def metrics(self, min_force_n: float) -> GripMetrics:
        """The run's grip metrics, held at ``min_force_n`` N per palm: each object's
        (:func:`experiment.metrics.grip_metrics`), then the worst of them
        (:func:`experiment.metrics.worst`)."""
        return worst(grip_metrics(self.samples(name), min_force_n) for name in self.objects)
