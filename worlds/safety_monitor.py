"""What a run is judged on, watched while the physics runs (:class:`SafetyMonitor`).

Every physics step: contacts between an obstacle and any robot link or object, and which of
them were a forearm's (PyBullet's contact points); a robot link other than a hand on the
table; the two arms touching; the fixtures' walls' forces and any robot body on them. Every
control step: the smallest FCL distance from the arms and the objects to the active
obstacles (and the forearms' and fixtures' own), and an object the palms held falling. The
counts are a :class:`SafetyRecord`, which the judge reads (:func:`experiment.judge.judge`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pybullet as pb

from skills.vocabulary import ARMS
from worlds.collision import FIXTURES, CollisionWorld, arm_group, welded_links
from worlds.fixtures import FixtureLog, wall_forces
from worlds.scene import Scene

#: A palm on an object, for the drop watch: a contact force over this, N.
DROP_TOUCH_N = 0.5


def touching(points: Sequence[Sequence[Any]]) -> bool:
    """Whether PyBullet contact points (``getContactPoints`` tuples) say two bodies touch: a
    point at or below zero distance, or one that carries a normal force.

    Bullet keeps a manifold's points a little past separation (positive distance, no force)
    so that contacts persist cheaply; such a point is a near miss, which the FCL clearance
    measures, not a contact.
    """
    return any(p[8] <= 0.0 or p[9] > 0.0 for p in points)


def _points_on(
    points: Sequence[Sequence[Any]], body: int, links: frozenset[int] | None
) -> list[Sequence[Any]]:
    """The contact points of ``points`` (obstacle as body A) on ``body``'s ``links`` (None:
    any of its links)."""
    return [p for p in points if p[2] == body and (links is None or p[4] in links)]


@dataclass
class SafetyRecord:
    """What the monitor saw over a run (the trial's success criteria).

    Attributes
    ----------
    obstacle_contacts : dict
        ``"<body> ~ <obstacle>"`` -> number of physics steps in contact.
    arm_contacts : int
        Physics steps with the two arms touching.
    min_obstacle_distance_m : float
        Smallest FCL distance from an arm link or the object to an active obstacle, m.
    closest : str
        What came closest to what.
    dropped : bool
        An object fell: above the table and touched by neither palm while moving down.
    drop_time : float or None
    dropped_object : str
        The object that fell first ("" if none did).
    spawned_inside : dict
        ``obstacle -> [bodies]``: an obstacle switched on where an object or an arm already
        was (PyBullet would push it out at once, or, for a fixed base, never).
    forearm_contacts : dict
        ``"<arm>_forearm ~ <obstacle>"`` -> physics steps with a forearm link
        (:attr:`worlds.robots.RobotModel.forearm_link_names`) touching it; these steps count
        in ``obstacle_contacts`` too, under the arm.
    min_forearm_distance_m : float
        Smallest FCL distance from a forearm link to an active obstacle, m.
    forearm_closest : str
        Which forearm link came closest to which obstacle.
    table_contacts : dict
        ``"<arm>_arm ~ table"`` -> physics steps with a link of the arm other than its hand
        (the palm and the links welded to it) touching the table: a wrist or forearm dragged
        over it, or pinned on it. A report, not a success criterion.
    """

    obstacle_contacts: dict[str, int] = field(default_factory=dict)
    arm_contacts: int = 0
    min_obstacle_distance_m: float = math.inf
    closest: str = ""
    dropped: bool = False
    drop_time: float | None = None
    dropped_object: str = ""
    spawned_inside: dict[str, list[str]] = field(default_factory=dict)
    forearm_contacts: dict[str, int] = field(default_factory=dict)
    min_forearm_distance_m: float = math.inf
    forearm_closest: str = ""
    table_contacts: dict[str, int] = field(default_factory=dict)


class SafetyMonitor:
    """Watches a scene for what a run is judged on and counts it in :attr:`record`.

    Parameters
    ----------
    scene : Scene
        The PyBullet scene.
    collision : CollisionWorld
        Its FCL mirror (synced by the caller before :meth:`after_control_step`).
    watched : tuple of str
        The objects watched for a drop.
    """

    def __init__(self, scene: Scene, collision: CollisionWorld, watched: tuple[str, ...]) -> None:
        self.scene = scene
        self.collision = collision
        self.watched = watched
        self.record = SafetyRecord()
        #: What the contact monitor watches against the obstacles, by label: the arms (a body
        #: and its links, None: all of them), the objects, and the forearms' links apart
        #: (fixed once the scene is built).
        robot = self.scene.robot
        self.watched_bodies: dict[str, tuple[int, frozenset[int] | None]] = {
            f"{a.value}_arm": (self.scene.robot_ids[robot.arms[a].body], self.scene.arm_links[a])
            for a in ARMS
        }
        self.watched_bodies.update({n: (b, None) for n, b in self.scene.object_ids.items()})
        # The groups whose clearance the judge watches every control step: both arms (palms
        # included) and every object.
        self.clearance_groups = (
            *(arm_group(a) for a in ARMS),
            *self.scene.object_ids,
        )
        self.forearm_links: dict[str, tuple[int, frozenset[int]]] = {}
        self.forearm_elements: list[str] = []
        for a in ARMS:
            names = robot.forearm_link_names.get(a, frozenset())
            if not names:
                continue
            body = self.scene.robot_ids[robot.arms[a].body]
            links = frozenset(
                j
                for j in range(pb.getNumJoints(body, physicsClientId=self.scene.client))
                if pb.getJointInfo(body, j, physicsClientId=self.scene.client)[12].decode() in names
            )
            self.forearm_links[f"{a.value}_forearm"] = (body, links)
            self.forearm_elements.extend(
                e for e in collision.arm_links(a) if e.split("/", 1)[1].split("#", 1)[0] in names
            )
        #: Per arm, its body and the links watched against the table: the arm's links but its
        #: hand (a palm may rest on the table beside a low object; a wrist may not).
        self.table_links: dict[str, tuple[int, frozenset[int]]] = {}
        client = self.scene.client
        for a in ARMS:
            arm = robot.arms[a]
            body = self.scene.robot_ids[arm.body]
            arm_links = self.scene.arm_links[a]
            if arm_links is None:
                arm_links = frozenset(range(pb.getNumJoints(body, physicsClientId=client)))
            hand = welded_links(body, arm.palm_link, client)
            self.table_links[f"{a.value}_arm"] = (body, frozenset(arm_links - hand - {-1}))
        #: The fixtures' walls' forces and the robot's touches, every physics step.
        self.fixture_log = FixtureLog(self.scene.physics_dt)
        #: The watched objects both palms have held off their support (see watch_drop).
        self._held_lifted: set[str] = set()
        self._rest_z = {
            o.name: float(o.position[2]) for o in self.scene.physical.objects
        }  # resting centre height, on the true table

    def after_physics_step(self) -> None:
        """The contacts of the step just taken (and the fixtures', where there are any)."""
        self.watch_contacts()
        if self.scene.fixture_ids:
            self.watch_fixtures()

    def after_control_step(self) -> None:
        """The clearances and drops at the end of a control step (the FCL mirror synced)."""
        self.watch_distances()
        if self.scene.fixture_ids:
            self.watch_fixture_distances()
        self.watch_drop()

    def watch_contacts(self) -> None:
        c = self.scene.client
        bodies = self.watched_bodies
        contacts = self.record.obstacle_contacts
        for name in self.scene.active_obstacles:
            # One query per obstacle: PyBullet gives every point of it with any body, each
            # turned to have the obstacle as body A (the same points, distances and forces as
            # one query per pair).
            points = pb.getContactPoints(bodyA=self.scene.obstacle_ids[name], physicsClientId=c)
            if not points:
                continue
            for label, (body, links) in bodies.items():
                if touching(_points_on(points, body, links)):
                    key = f"{label} ~ {name}"
                    contacts[key] = contacts.get(key, 0) + 1
            for label, (body, links) in self.forearm_links.items():
                if touching(_points_on(points, body, links)):
                    key = f"{label} ~ {name}"
                    forearm = self.record.forearm_contacts
                    forearm[key] = forearm.get(key, 0) + 1
        # One query for the table too, sorted by arm (the iCub's two arms share one body).
        points = pb.getContactPoints(bodyA=self.scene.table_id, physicsClientId=c)
        for label, (body, links) in self.table_links.items():
            if points and touching(_points_on(points, body, links)):
                key = f"{label} ~ table"
                self.record.table_contacts[key] = self.record.table_contacts.get(key, 0) + 1
        (left, left_links), (right, right_links) = bodies["left_arm"], bodies["right_arm"]
        if left != right:
            if touching(pb.getContactPoints(bodyA=left, bodyB=right, physicsClientId=c)):
                self.record.arm_contacts += 1
        elif left_links is not None and right_links is not None:
            # One body carrying both arms: its own contacts between the two arms' links.
            points = pb.getContactPoints(bodyA=left, bodyB=left, physicsClientId=c)
            if touching(
                [
                    p
                    for p in points
                    if (p[3] in left_links and p[4] in right_links)
                    or (p[3] in right_links and p[4] in left_links)
                ]
            ):
                self.record.arm_contacts += 1

    def watch_fixtures(self) -> None:
        """Each fixture's walls' forces on the objects, and any robot body touching it."""
        c = self.scene.client
        log = self.fixture_log
        for f in self.scene.physical.fixtures:  # where they stand, to tell their walls apart
            body = self.scene.fixture_ids[f.name]
            forces = np.zeros(4)
            for obj in self.scene.object_ids.values():
                forces += wall_forces(c, body, f, obj)
            log.wall_forces.setdefault(f.name, []).append(forces)
            points = pb.getContactPoints(bodyA=body, physicsClientId=c)
            if not points:
                continue
            for a in ARMS:
                robot_body, links = self.watched_bodies[f"{a.value}_arm"]
                if touching(_points_on(points, robot_body, links)):
                    key = f"{a.value}_arm ~ {f.name}"
                    log.robot_contacts[key] = log.robot_contacts.get(key, 0) + 1

    def watch_fixture_distances(self) -> None:
        """The arms' (palms included) smallest FCL distance to a fixture's walls."""
        log = self.fixture_log
        for arm in ARMS:
            prox = self.collision.closer_than(arm_group(arm), FIXTURES, log.min_robot_distance_m)
            if prox is not None:
                log.min_robot_distance_m = prox.distance
                log.robot_closest = f"{prox.element_a} ~ {prox.element_b}"

    def watch_distances(self) -> None:
        if not self.scene.active_obstacles:
            return
        for group in self.clearance_groups:
            prox = self.collision.closer_than(
                group, "obstacles", self.record.min_obstacle_distance_m
            )
            if prox is not None:
                self.record.min_obstacle_distance_m = prox.distance
                self.record.closest = f"{prox.element_a} ~ {prox.element_b}"
        if self.forearm_elements:
            forearm = self.collision.elements_closer_than(
                self.forearm_elements, "obstacles", self.record.min_forearm_distance_m
            )
            if forearm is not None:
                self.record.min_forearm_distance_m = forearm.distance
                self.record.forearm_closest = f"{forearm.element_a} ~ {forearm.element_b}"

    def watch_drop(self) -> None:
        """A drop: an object the palms have held off its support, in the air and falling with
        neither palm on it. One shoved or tipped up without having been held (a palm or a
        wrist knocking it as it stands) is not dropped: where that leaves it is judged."""
        for name in self.watched:
            pos, _ = self.scene.object_pose(name)
            lifted = pos[2] > self._rest_z[name] + 0.01
            if not lifted:
                # Set down: a later fall is a drop only if the palms have lifted it again (a
                # parcel placed, let go, then swept off the table by an arm was no drop).
                self._held_lifted.discard(name)
                continue
            if self.record.dropped:
                continue
            # The contact forces are read only for a lifted object (reads, no effect): once
            # to see it held, then only as it falls.
            if name not in self._held_lifted:
                if all(self.scene.palm_contact_force(a, name) > DROP_TOUCH_N for a in ARMS):
                    self._held_lifted.add(name)
                continue
            vel, _ = self.scene.object_velocity(name)
            if vel[2] < -0.2 and not any(
                self.scene.palm_contact_force(a, name) > DROP_TOUCH_N for a in ARMS
            ):
                self.record.dropped = True
                self.record.drop_time = self.scene.time
                self.record.dropped_object = name


__all__ = ["DROP_TOUCH_N", "SafetyMonitor", "SafetyRecord", "touching"]
