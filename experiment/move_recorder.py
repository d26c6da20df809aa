"""What an episode keeps of each move as the tree runs: the object's path, its placement and
error, the composition and skill that placed it, and the grip metrics' samples.

:func:`experiment.episode.run_episode` adds a :class:`MoveRecorder` as a post-tick handler of
its tree and reads it when the run ends.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
import py_trees
from py_trees.common import Status

from experiment.figures import MoveTrace, OtherObject, demonstrated_path
from experiment.grip_recorder import GripRecorder
from experiment.judge import move_labels
from planner.move_result import MoveResult, move_placements, move_results
from planner.port import Move
from skills import quaternion as quat
from skills.library import SkillLibrary
from worlds.sim_world import SimWorld
from worlds.trays import riders
from worlds.truth import true_goal_position

#: A move's object that goes this far across the table (m, its centre's horizontal path)...
SLID_TRAVEL_M = 0.05
#: ...never rising this much above where its carry began (m) was slid, not carried.
SLID_LIFT_M = 0.01


@dataclass
class MoveTrack:
    """What the recorder keeps of one move."""

    positions: list[np.ndarray] = field(default_factory=list)
    orientations: list[np.ndarray] = field(default_factory=list)
    start: tuple[np.ndarray, np.ndarray] | None = None
    obstacles: tuple[str, ...] = ()
    #: The other objects' poses (name, position, quaternion) as the move started.
    others: tuple[tuple[str, np.ndarray, np.ndarray], ...] = ()
    error_m: float | None = None
    error_deg: float | None = None
    composition: dict[str, float] | None = None
    skill: str | None = None
    #: The move's latest success the errors were taken from.
    placed: MoveResult | None = None
    #: The object's pose (position, quaternion) when that success was seen.
    placed_pose: tuple[np.ndarray, np.ndarray] | None = None


class MoveRecorder:
    """Post-tick bookkeeping: each move's object path and placement error, for every object,
    and the samples of the grip metrics.

    It reads the moves' published results (:func:`planner.move_result.move_results`,
    written by the Transport leaves), not the leaves: while a move's latest result is RUNNING
    the carried object's measured pose is sampled into that move's path; at each new success
    (:func:`planner.move_result.move_placements`) the move's placement error, composition
    and skill are kept. Every tick its
    :class:`experiment.grip_recorder.GripRecorder` samples the objects and palms, and the
    poses it read are the ones the paths keep.
    """

    def __init__(
        self,
        sim: SimWorld,
        moves: list[tuple[str, int]],
        stepped: dict[str, tuple[Move, ...]],
        control_dt: float,
    ) -> None:
        self.sim = sim
        self.grip = GripRecorder(sim, control_dt)
        self.order = {key: i for i, key in enumerate(moves)}
        self.tracks = {key: MoveTrack() for key in moves}
        self.current: tuple[str, int] | None = None
        self.stepped = stepped
        #: The moves judged: the last step of each file move, in task order.
        self.finals = [k for k in moves if stepped[k[0]][k[1]].final]
        #: Where the objects the task leaves standing stand at the start (true poses): not
        #: the task's, nor riding loose on one of them (a tray's balls, judged with it).
        spec_objects = sim.scene.spec.objects
        tasked = {name for name, _ in moves}
        riding = {o.name for t in tasked for o in riders(spec_objects, t, tuple(tasked))}
        self.standing = {
            o.name: sim.scene.object_pose(o.name)
            for o in spec_objects
            if o.name not in tasked and o.name not in riding
        }

    def _steps_of(self, key: tuple[str, int]) -> list[tuple[str, int]]:
        """The robot's moves that make the file move whose last step is ``key``."""
        task_move = self.stepped[key[0]][key[1]].task_move
        return [
            k
            for k in self.order
            if k[0] == key[0] and (self.stepped[k[0]][k[1]].task_move == task_move)
        ]

    def __call__(self, tree: py_trees.trees.BehaviourTree) -> None:
        poses = self.grip.sample()
        # In task order, as a move that ends and the next that starts share a tick.
        results = [(k, r) for k, r in move_results().items() if k in self.order]
        for key, result in sorted(results, key=lambda kr: self.order[kr[0]]):
            track = self.tracks[key]
            pose = poses[key[0]]
            if result.status == Status.RUNNING:
                if track.start is None:
                    track.start = (pose.position.copy(), pose.orientation.copy())
                    track.obstacles = tuple(o.name for o in self.sim.obstacles())
                    track.others = tuple(
                        (n, p.position.copy(), p.orientation.copy())
                        for n, p in poses.items()
                        if n != key[0]
                    )
                track.positions.append(pose.position.copy())
                track.orientations.append(pose.orientation.copy())
                self.current = key
            elif result.status == Status.SUCCESS and self.current == key:
                track.positions.append(pose.position.copy())
                track.orientations.append(pose.orientation.copy())
                self.current = None
        # A move's placement is its latest success, seen even when a correction that started
        # in the same tick replaced it as the move's latest result.
        for key, placed in move_placements().items():
            if key not in self.tracks or placed is self.tracks[key].placed:
                continue
            track = self.tracks[key]
            assert placed.placement_error_m is not None
            assert placed.placement_error_rad is not None
            track.placed = placed
            pose = poses[key[0]]
            track.placed_pose = (pose.position.copy(), pose.orientation.copy())
            track.error_m = self._true_error_m(key, pose.position, placed.placement_error_m)
            track.error_deg = float(np.degrees(placed.placement_error_rad))
            track.composition = {
                "transport_weight": placed.transport_weight,
                "avoid_gain": placed.avoid_gain,
            }
            track.skill = placed.skill

    def _true_error_m(self, key: tuple[str, int], position: np.ndarray, told: float) -> float:
        """The placement error judged on the physics: ``told`` (the leaf's, from the goal as
        the file states it) unless the truth moved the table, then from the goal on the true
        table top (:func:`worlds.truth.true_goal_position`), or the move's fixture, then from
        its goal moved with it."""
        truth = self.sim.scene.truth
        move = self.stepped[key[0]][key[1]]
        if move.fixture is not None:
            shift = truth.fixture_shift(move.fixture)
            if not shift.any():
                return told
            return float(np.linalg.norm(position - np.asarray(move.goal.position) - shift))
        true_goal = self._true_table_goal(key)
        if true_goal is None:
            return told
        return float(np.linalg.norm(position - true_goal))

    def _true_table_goal(self, key: tuple[str, int]) -> np.ndarray | None:
        """Move ``key``'s goal on the true table top (:func:`worlds.truth.true_goal_position`),
        or None when the truth left the table where the file states it."""
        dz = self.sim.scene.truth.table_dz_m
        if not dz:
            return None
        goal = self.stepped[key[0]][key[1]].goal
        return np.asarray(
            true_goal_position(
                goal.position,
                goal.orientation,
                self.sim.object_extents(key[0]),
                self.sim.spec.scene.table.position[2],
                dz,
            ),
            dtype=float,
        )

    def goal_shift(self, key: tuple[str, int]) -> np.ndarray:
        """Where move ``key``'s goal is judged less where the file states it, m (3,): its
        fixture's shift, or the goal moved onto the true table top; zero when the truth moved
        neither (for drawing: the judge's own arithmetic is :meth:`_true_error_m`'s)."""
        move = self.stepped[key[0]][key[1]]
        if move.fixture is not None:
            return np.asarray(self.sim.scene.truth.fixture_shift(move.fixture), dtype=float)
        true_goal = self._true_table_goal(key)
        if true_goal is None:
            return np.zeros(3)
        return true_goal - np.asarray(move.goal.position, dtype=float)

    def moved_since_placed(self) -> list[tuple[str, float, float]]:
        """Per object whose last move was placed: how far (m) and how much (deg) it lies now
        from where that placement left it (the robot may knock a placed object as it goes on
        to the next, or as it retreats)."""
        last: dict[str, tuple[np.ndarray, np.ndarray]] = {}
        for name, index in self.finals:
            placed = self.tracks[name, index].placed_pose
            if placed is not None:
                last[name] = placed
            else:
                last.pop(name, None)
        out = []
        for name, (position, orientation) in last.items():
            pose = self.sim.object_pose(name)
            out.append((name, *_offset(pose.position, pose.orientation, position, orientation)))
        return out

    def slid(self) -> list[tuple[str, float, float]]:
        """Per judged move whose object went :data:`SLID_TRAVEL_M` or more across the table
        without rising :data:`SLID_LIFT_M` above where its carry began: its label, the
        horizontal path it went (m) and the most it rose (m). A carry the avoidance pressed
        down can push the object to its goal along the table top, placed as well as a lifted
        one would be: this says so."""
        out = []
        for label, key in zip(move_labels([k[0] for k in self.finals]), self.finals, strict=True):
            path = [p for k in self._steps_of(key) for p in self.tracks[k].positions]
            if len(path) < 2:
                continue
            xyz = np.asarray(path, dtype=float)
            travel = float(np.sum(np.linalg.norm(np.diff(xyz[:, :2], axis=0), axis=1)))
            lift = float(np.max(xyz[:, 2]) - xyz[0, 2])
            if travel >= SLID_TRAVEL_M and lift < SLID_LIFT_M:
                out.append((label, travel, lift))
        return out

    def standing_moved(self) -> list[tuple[str, float, float]]:
        """Per object the task leaves standing (:attr:`standing`): how far (m) and how much
        (deg) it lies now from where it stood at the start (an arm or the carried object may
        shove it on the way)."""
        return [
            (name, *_offset(*self.sim.scene.object_pose(name), position, orientation))
            for name, (position, orientation) in self.standing.items()
        ]

    def column(self, what: str) -> list[Any]:
        """One attribute of every judged move's track (its last step's), in task order."""
        return [getattr(self.tracks[key], what) for key in self.finals]

    def traces(self, library: SkillLibrary) -> list[MoveTrace]:
        """Every move of the task as the figure draws it."""
        spec = self.sim.spec
        shapes = {o.name: o.shape for o in spec.scene.objects}
        initial = {o.name: (o.position, o.quaternion) for o in spec.scene.objects}
        obstacles = {o.name: o for o in spec.scene.obstacles}
        goals = {name: spec.moves_of(name) for name, _ in self.order}
        out = []
        for label, key in zip(move_labels([k[0] for k in self.finals]), self.finals, strict=True):
            track = self.tracks[key]
            steps = [self.tracks[k] for k in self._steps_of(key)]
            task_move = self.stepped[key[0]][key[1]].task_move
            goal = goals[key[0]][task_move if task_move is not None else key[1]]
            goal_q = np.asarray(goal.goal_quaternion, dtype=float)
            first = next((t.start for t in steps if t.start is not None), None)
            if first is None:
                # Never started: it would have started where the object rests, at its last
                # goal or where the world puts it.
                at = task_move if task_move is not None else key[1]
                before = goals[key[0]][at - 1] if at > 0 else None
                pose = (
                    initial[key[0]]
                    if before is None
                    else (before.goal_position, before.goal_quaternion)
                )
                first = (np.asarray(pose[0], dtype=float), np.asarray(pose[1], dtype=float))
            start = first
            started = next((t for t in steps if t.start is not None), None)
            others = (
                started.others
                if started is not None
                else tuple(
                    (n, self.sim.object_pose(n).position, self.sim.object_pose(n).orientation)
                    for n in shapes
                    if n != key[0]
                )
            )
            positions = [p for t in steps for p in t.positions]
            orientations = [q for t in steps for q in t.orientations]
            skill = (
                library.get(track.skill)
                if track.skill is not None and track.skill in library
                else None
            )
            out.append(
                MoveTrace(
                    label,
                    start[0],
                    # Where it is judged: on the true table, with its fixture (Hard mode).
                    np.asarray(goal.goal_position, dtype=float) + self.goal_shift(key),
                    np.array(positions).reshape(-1, 3),
                    # A move never carried: the obstacles the task gives it, as they would be.
                    tuple(
                        obstacles[n]
                        for n in (started.obstacles if started is not None else goal.obstacles)
                    ),
                    start_orientation=start[1],
                    goal_orientation=goal_q,
                    orientations=np.array(orientations).reshape(-1, 4),
                    shape=shapes[key[0]],
                    skill=track.skill,
                    fixtures=tuple(spec.scene.fixtures),
                    others=tuple(OtherObject(n, shapes[n], p, q) for n, p, q in others),
                    demonstrated=(
                        demonstrated_path(skill, start[0], start[1], goal.goal_position, goal_q)
                        if skill is not None
                        else None
                    ),
                )
            )
        return out


__all__ = ["MoveRecorder", "MoveTrack"]


def _offset(
    position: np.ndarray, orientation: np.ndarray, was: np.ndarray, was_turned: np.ndarray
) -> tuple[float, float]:
    """How far (m) and how much (deg) a pose lies from another."""
    turn = float(np.degrees(quat.angle_between(orientation, was_turned)))
    return float(np.linalg.norm(np.asarray(position) - was)), turn
