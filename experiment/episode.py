"""One run of a world: build the scene, run the tree, judge it, write what it shows.

Used by ``app.py run`` (one episode with all its outputs) and ``app.py trials`` (many, lean).
A run succeeds only if the tree succeeds and every criterion of the paper's experiment holds,
for every object of the world's task: each of its moves placed (a move without a placement
fails the run, naming the object and move), within 2 cm and 10 degrees of its goal as
measured, no object ever dropped, no robot link and no object touching an obstacle (PyBullet
contacts and FCL distance), and the arms never touching each other.
"""

from __future__ import annotations

import math
import os
import shutil
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import py_trees

import planner.leaves  # noqa: F401  (registers the leaves for the XML loader)
from duet_robot.text import printable
from experiment.figures import Animation, trajectory_figure
from experiment.insertion import insertion_verdict
from experiment.judge import CLOSEST_VS_CONTACTS, judge, knocked_away, move_labels
from experiment.metrics import GripMetrics
from experiment.move_recorder import MoveRecorder
from experiment.tray import tray_verdicts
from planner.atomic_file import atomic_open, stale_temporaries
from planner.btlog import BtLog
from planner.default_tree import TaskStep, default_tree
from planner.leaves.approach import off_the_table
from planner.leaves.conditions import IsHeld
from planner.loader import load_tree
from planner.port import Move
from planner.render import render_tree
from planner.runlog import RunLog
from planner.runner import progress_node, readable, run_tree
from planner.tree_dataflow import RUN_WRITES, TASK_OBJECT_KEY
from skills.default_library import default_library
from skills.library import SkillLibrary
from worlds.sim_world import SimWorld, task_moves
from worlds.truth import PhysicalTruth
from worlds.world_file import World, as_world_spec

#: An object is held, for the grip metrics, while both palms press on it with at least this
#: force, N: the default ``min_force_n`` of the IsHeld leaf (and of Transport and Turning).
HELD_FORCE_N = float(IsHeld.INPUT_PORTS["min_force_n"].default_value)
#: A run whose grip slipped further than this along a face is told so in its text, mm: the
#: slide the shipped trees' IsHeld takes for a broken grip (its ``max_slip_m`` default). A
#: push that shoved the parcel 12 cm through the palms had been said only in the JSON.
SLIP_NOTE_MM = 1000.0 * float(IsHeld.INPUT_PORTS["max_slip_m"].default_value)


@dataclass
class EpisodeReport:
    """Everything a run is judged on, JSON-ready via :meth:`summary`."""

    success: bool
    tree_status: str
    reason: str
    #: One entry per move of the task, over all its objects, in task order; None: not placed.
    placement_error_m: list[float | None]
    placement_error_deg: list[float | None]
    min_obstacle_distance_m: float
    obstacle_contacts: dict[str, int]
    arm_contacts: int
    dropped: bool
    sim_time_s: float
    wall_time_s: float
    failure: str = ""
    outputs: dict[str, str] = field(default_factory=dict)
    #: Outputs that could not be written after the verdict, each naming its file and why.
    output_errors: list[str] = field(default_factory=list)
    #: Outputs of an earlier run this one replaced (links among them removed, not followed).
    replaced_outputs: list[str] = field(default_factory=list)
    #: Where the outputs of a run killed in ``out`` before this one were kept, if any.
    killed_run_outputs: Path | None = None
    #: Per move, the composition that placed the object: ``{"transport_weight": w,
    #: "avoid_gain": g}`` of the Transport leaf that succeeded (its published
    #: :class:`planner.move_result.MoveResult`), or None if none did.
    compositions: list[dict[str, float] | None] = field(default_factory=list)
    #: Per move, the object it moves (parallel to ``placement_error_m``).
    placement_objects: list[str] = field(default_factory=list)
    #: Per move, the learnt transport skill its Transport ran (``MoveResult.skill``), or None.
    skills: list[str | None] = field(default_factory=list)
    #: Wall time inside the physics engine's steps alone, s (no control, tree or checks).
    physics_wall_s: float = 0.0
    #: Wall time computing and sending the torques before each physics step, s.
    control_wall_s: float = 0.0
    #: Wall time watching contacts every physics step and clearances every control step, s.
    watch_wall_s: float = 0.0
    #: Per disturbance of the world, in file order, what it did
    #: (:meth:`worlds.disturbances.AppliedDisturbance.summary`); empty for a world without.
    disturbances: list[dict[str, Any]] = field(default_factory=list)
    #: How the objects were carried: slip, tilt, jerk, squeeze, grasps
    #: (:class:`experiment.metrics.GripMetrics`, the worst over objects).
    grip: GripMetrics = field(default_factory=GripMetrics)
    #: Physics steps with a forearm touching an obstacle, by ``"<arm>_forearm ~ <obstacle>"``
    #: (counted in ``obstacle_contacts`` too, under the arm).
    forearm_contacts: dict[str, int] = field(default_factory=dict)
    #: Smallest FCL distance from a forearm to an active obstacle, m (inf: none measured).
    min_forearm_distance_m: float = math.inf
    #: Physics steps with an arm's link other than its hand touching the table, by
    #: ``"<arm>_arm ~ table"`` (:attr:`worlds.safety_monitor.SafetyRecord.table_contacts`).
    table_contacts: dict[str, int] = field(default_factory=dict)
    #: Per carried tray and ball loose on it, its peak tilt and the ball's path relative to
    #: the tray (:meth:`experiment.tray.TrayVerdict.summary`); empty without trays.
    tray: list[dict[str, Any]] = field(default_factory=list)
    #: A world with fixtures: the insertion's figures (:mod:`experiment.insertion`).
    insertion: dict[str, Any] = field(default_factory=dict)
    #: Per move whose object was pushed along the table top rather than lifted
    #: (:meth:`experiment.move_recorder.MoveRecorder.slid`): its label, path (m) and most
    #: rise (m). Printed, not judged nor kept in the summary.
    slid: list[tuple[str, float, float]] = field(default_factory=list)
    #: Each object that ends beyond the placement tolerance from where its last move placed
    #: it, or a bystander from where it stood (:func:`knocked_away`): said under a failure
    #: whose reason is another, not judged again nor recorded.
    knocked: list[str] = field(default_factory=list)

    def summary(self) -> dict[str, Any]:
        """Plain JSON-safe dictionary (infinite distances as None).

        A world with disturbances adds ``"disturbances": {"applied": n, "entries": [...]}``:
        how many acted on at least one physics step, and per entry the steps it acted on. A
        world without has no such key, so its records read as they did before.
        """
        d = self.min_obstacle_distance_m
        forearm = self.min_forearm_distance_m
        extra: dict[str, Any] = {}
        if self.disturbances:
            applied = sum(1 for e in self.disturbances if e["steps"] > 0)
            extra["disturbances"] = {"applied": applied, "entries": self.disturbances}
        if self.tray:
            extra["tray"] = self.tray
        if self.insertion:
            extra["insertion"] = self.insertion
        return {
            "success": self.success,
            "failure": self.failure,
            "tree_status": self.tree_status,
            "reason": self.reason,
            "placement_error_m": self.placement_error_m,
            "placement_error_deg": self.placement_error_deg,
            "placement_objects": self.placement_objects,
            "min_obstacle_distance_m": None if math.isinf(d) else round(d, 5),
            "obstacle_contacts": self.obstacle_contacts,
            "arm_contacts": self.arm_contacts,
            "forearm_contacts": self.forearm_contacts,
            "min_forearm_distance_m": None if math.isinf(forearm) else round(forearm, 5),
            "table_contacts": self.table_contacts,
            "dropped": self.dropped,
            **self.grip.summary(),
            "sim_time_s": round(self.sim_time_s, 3),
            "wall_time_s": round(self.wall_time_s, 3),
            "physics_wall_s": round(self.physics_wall_s, 3),
            "control_wall_s": round(self.control_wall_s, 3),
            "watch_wall_s": round(self.watch_wall_s, 3),
            "compositions": self.compositions,
            "skills": self.skills,
            **extra,
            "outputs": self.outputs,
        }

    def lines(self, name: str) -> list[str]:
        """The run as ``app.py run`` prints it: the verdict for world ``name``, each move's
        placement, the closest approaches, the table's and the disturbances' contacts, the
        speed and what was written (text from files made safe for a terminal)."""
        s = self.summary()
        verdict = "SUCCESS" if self.success else f"FAILURE ({printable(self.failure)})"
        out = [f"{printable(name)}: {verdict}"]
        for label, e, d in zip(
            move_labels(self.placement_objects),
            self.placement_error_m,
            self.placement_error_deg,
            strict=True,
        ):
            placed = "not placed" if e is None or d is None else f"{e * 1000:.1f} mm, {d:.1f} deg"
            out.append(f"  {printable(label)}: {placed}")
        for line in self.knocked:
            if not self.success and line not in self.failure:
                out.append(f"  {printable(line)}")
        for label, travel, lift in self.slid:
            out.append(
                f"  {printable(label)}: slid along the table top, not lifted: its centre went "
                f"{travel * 1000:.0f} mm and rose at most {lift * 1000:.1f} mm"
            )
        slip = s.get("slip_mm")
        if slip is not None and slip > SLIP_NOTE_MM:
            out.append(
                f"  grip: slipped {slip:.0f} mm along a face while held (more than the "
                f"{SLIP_NOTE_MM:.0f} mm a grip is taken for broken at; slip_mm)"
            )
        dist = s["min_obstacle_distance_m"]
        out.append(
            "  closest approach to an obstacle: "
            f"{'no obstacle' if dist is None else f'{dist * 1000:.1f} mm'}"
            + _apart(dist, sum(s["obstacle_contacts"].values()))
        )
        forearm = s["min_forearm_distance_m"]
        if forearm is not None or s["forearm_contacts"]:
            touching = sum(s["forearm_contacts"].values())
            out.append(
                f"  forearms: {touching} physics steps touching an obstacle; closest approach "
                f"{'n/a' if forearm is None else f'{forearm * 1000:.1f} mm'}"
                + _apart(forearm, touching)
            )
        for key, steps in s["obstacle_contacts"].items():  # shown though the failure is another
            out.append(f"  {printable(key)}: {steps} physics steps touching")
        for key, steps in s.get("table_contacts", {}).items():
            out.append(f"  {printable(key)}: {steps} physics steps (a link other than the hand)")
        if "disturbances" in s:
            pushes = s["disturbances"]
            out.append(f"  disturbances applied: {pushes['applied']} of {len(pushes['entries'])}")
            later = 0
            for entry in pushes["entries"]:
                if entry["steps"]:
                    steps = f"physics steps {entry['first_step']} to {entry['last_step']}"
                elif entry.get("skipped"):
                    steps = (
                        "skipped: the object was not carried (held by both palms, off its "
                        "support) when its window opened"
                    )
                elif entry["at_s"] >= self.sim_time_s:
                    later += 1  # drawn for a run that ended before them: one line for all
                    continue
                else:
                    steps = "no physics step (none of the run started inside its window)"
                out.append(f"    {printable(entry['object'])} at {entry['at_s']:g} s: {steps}")
            if later:
                out.append(f"    {later} more set for after the run ended")
        out.append(
            f"  simulated {self.sim_time_s:.1f} s in {self.wall_time_s:.1f} s wall "
            f"({self.sim_time_s / max(self.wall_time_s, 1e-9):.1f}x real time)"
        )
        out += [f"  {key}: {path}" for key, path in self.outputs.items()]
        return out


def load_library(world: World) -> SkillLibrary:
    """The world's skill library: the default one, or a folder (LibraryFileError if bad)."""
    if world.skills.library == "default":
        return default_library()
    return SkillLibrary.load(world.resolve_path(world.skills.library))


def robot_moves(world: World) -> dict[str, tuple[Move, ...]]:
    """Each object's moves as the robot makes them: a turn its grip cannot make in one grasp
    is several moves (:func:`worlds.sim_world.task_moves`), each naming its file move."""
    spec = as_world_spec(world)
    return {step.object: task_moves(spec, step.object) for step in world.task}


def task_steps(world: World) -> list[TaskStep]:
    """The world's task for :func:`planner.default_tree.default_tree`: per step, its object,
    number of moves (as the robot makes them) and the index of its first among that object's
    moves."""
    stepped = robot_moves(world)
    done: dict[str, int] = {}
    steps = []
    for step in world.task:
        first_file = done.get(step.object, 0)
        files = range(first_file, first_file + len(step.moves))
        indices = [i for i, m in enumerate(stepped[step.object]) if m.task_move in files]
        of = tuple(int(stepped[step.object][i].task_move or 0) for i in indices)
        steps.append(TaskStep(step.object, len(indices), indices[0] if indices else 0, of))
        done[step.object] = first_file + len(step.moves)
    return steps


def move_keys(world: World) -> list[tuple[str, int]]:
    """Every move the robot makes, ``(object, index among its moves)``, in task order."""
    return [(s.object, s.first_move + i) for s in task_steps(world) for i in range(s.moves)]


def _apart(distance: float | None, touching: int) -> str:
    """Why a closest approach over 0 stands beside contacts: two measures, not a clash."""
    if distance is None or distance <= 0.0 or not touching:
        return ""
    return f" ({CLOSEST_VS_CONTACTS})"


def _a_file(path: Path) -> bool:
    """A file or a link (never followed), not a folder."""
    return path.is_symlink() or path.is_file()


#: What a run writes into its ``out`` folder.
OUTPUT_NAMES = ("run.jsonl", "run.btlog", "trajectories.png", "animation.gif", "tree.svg")


#: The folder inside ``out`` that holds an earlier run's outputs while this one runs.
EARLIER = ".earlier-run"
#: The folder inside ``out`` where a run stopped by an error leaves what it wrote, when an
#: earlier run's outputs are put back in its place.
STOPPED = "stopped-run"


def _keep_stopped(out: Path, written: list[str]) -> Path | None:
    """Move a stopped run's outputs ``written`` (names in ``out``), and those it was still
    writing (their temporaries, :func:`planner.atomic_file.stale_temporaries`, under their
    own names), into a fresh ``out/stopped-run``; one already there is moved on to the first
    free ``stopped-run.N`` first. The folder, or None if there was nothing to keep."""
    moves = [(out / name, name) for name in written]
    for name in OUTPUT_NAMES:
        temporaries = stale_temporaries(out, name)
        if temporaries and name not in written:  # the latest of them, under its own name
            moves.append((max(temporaries, key=lambda p: p.stat().st_mtime), name))
    if not moves:
        return None
    stopped = out / STOPPED
    if stopped.is_symlink() or stopped.exists():
        n = 1
        while (out / f"{STOPPED}.{n}").is_symlink() or (out / f"{STOPPED}.{n}").exists():
            n += 1
        os.replace(stopped, out / f"{STOPPED}.{n}")
    stopped.mkdir()
    for path, name in moves:
        os.replace(path, stopped / name)
    for name in OUTPUT_NAMES:  # temporaries older than those kept: empty or superseded
        for stale in stale_temporaries(out, name):
            stale.unlink()
    return stopped


class EarlierOutputs:
    """An earlier run's outputs in ``out``, set aside while this run writes its own: put back
    if this run stops with an error (a bad leaf, a port taken, Ctrl-C), so that nothing
    already written is lost (what the stopped run wrote goes to ``out/stopped-run``);
    dropped once it has run.

    A link is moved itself, never followed: writing through a link named like an output would
    overwrite whatever it points at, outside ``out``.

    Raises
    ------
    OSError
        If an output's name is a folder, or the outputs cannot be moved.
    """

    def __init__(self, out: Path) -> None:
        self.out = out
        self.folder = out / EARLIER
        if self.folder.is_symlink() or self.folder.is_file():
            self.folder.unlink()
        #: Where a killed run's outputs were kept as this one began (None: there were none).
        self.kept_stopped: Path | None = None
        #: Where :meth:`restore` last moved a stopped run's outputs (None: nowhere).
        self.stopped_to: Path | None = None
        if self.folder.is_dir() and not self.folder.is_symlink():
            # A run killed before it put them back or dropped them: as if it had stopped.
            self.names = [n for n in OUTPUT_NAMES if _a_file(self.folder / n)]
            self.restore()
            self.kept_stopped = self.stopped_to
        # A killed run's outputs it was still writing (never renamed from their temporaries):
        # what it wrote, up to where it was killed, kept, not deleted.
        self.kept_stopped = _keep_stopped(out, []) or self.kept_stopped
        for name in OUTPUT_NAMES:
            path = out / name
            if path.exists() and not _a_file(path):
                raise OSError(f"{path}: expected a file this run may replace, got a folder")
        #: The earlier run's outputs, by name, as set aside.
        self.names = [n for n in OUTPUT_NAMES if _a_file(out / n)]
        if self.names:
            self.folder.mkdir()
            for name in self.names:
                os.replace(out / name, self.folder / name)

    def restore(self) -> str:
        """After a run stopped with an error: the earlier run's outputs put back, and this
        run's, if it wrote any beside them, moved to ``out/stopped-run`` (a stopped run's
        before it there moved on to ``stopped-run.1``, ``.2``...: never deleted), those it was
        still writing too; with no earlier outputs, this run's stay where they are. What
        became of them, for the user ("" if nothing was moved)."""
        if not self.names:
            return ""
        written = [n for n in OUTPUT_NAMES if _a_file(self.out / n)]
        stopped = self.stopped_to = _keep_stopped(self.out, written)
        for name in self.names:
            os.replace(self.folder / name, self.out / name)
        self.drop()
        kept = f"; what it wrote is in {stopped}" if stopped is not None else ""
        return f"the earlier run's outputs are back in {self.out}{kept}"

    def drop(self) -> None:
        """The earlier run's outputs removed for good."""
        if self.folder.is_dir() and not self.folder.is_symlink():
            shutil.rmtree(self.folder)


def run_episode(
    world: World,
    tree_path: Path | None = None,
    library: SkillLibrary | None = None,
    out: Path | None = None,
    animation: bool = True,
    progress: Callable[[float, str, str], None] | None = None,
    gui: bool = False,
    main_tree: str | None = None,
    groot_port: int | None = None,
    truth: PhysicalTruth | None = None,
) -> EpisodeReport:
    """Run the world's task once and judge it.

    Parameters
    ----------
    world : World
    tree_path : Path, optional
        Behaviour tree XML; default: :func:`planner.default_tree.default_tree` for the
        world's task (``planner/trees/pick_and_place.xml`` with one PickAndPlace per step of
        the task, each with its moves). The blackboard's ``/object`` names the task's first
        object, for trees that read it.
    library : SkillLibrary, optional
        Default: the world's.
    out : Path, optional
        Folder for ``run.jsonl``, ``run.btlog`` (Groot2's replay), ``trajectories.png``,
        ``animation.gif`` and ``tree.svg``; None writes nothing.
    animation : bool
        Capture frames with the CPU renderer (slower).
    progress : callable (sim_time, leaf_name, feedback), optional
        Called when the running leaf changes.
    gui : bool
        Show PyBullet's window (needs a display; :class:`worlds.scene.NoDisplayError`).
    main_tree : str, optional
        The ``<BehaviorTree ID>`` of ``tree_path`` to run instead of its
        ``main_tree_to_execute`` (a file saved by Groot2 has none).
    groot_port : int, optional
        Serve the run's status live to Groot2 on this port
        (:class:`planner.groot_publisher.GrootPublisher`; needs ``out``).
    truth : PhysicalTruth, optional
        How the physics differs from ``world`` (:mod:`worlds.truth`): only the scene sees it;
        the tree, the skills and the reasoner read ``world``. None: in nothing.

    Raises
    ------
    planner.loader.TreeFileError, skills.library.LibraryFileError
        On bad input files (the caller turns them into exit code 2).
    """
    if out is None:
        return _episode(
            world, tree_path, library, None, animation, progress, gui, main_tree, groot_port, truth
        )
    out.mkdir(parents=True, exist_ok=True)
    earlier = EarlierOutputs(out)
    try:
        report = _episode(
            world, tree_path, library, out, animation, progress, gui, main_tree, groot_port, truth
        )
    except BaseException as err:
        told = earlier.restore()
        if told:
            err.add_note(told)
        raise
    earlier.drop()
    report.replaced_outputs = list(earlier.names)
    report.killed_run_outputs = earlier.kept_stopped
    return report


def _episode(
    world: World,
    tree_path: Path | None,
    library: SkillLibrary | None,
    out: Path | None,
    animation: bool,
    progress: Callable[[float, str, str], None] | None,
    gui: bool,
    main_tree: str | None,
    groot_port: int | None,
    truth: PhysicalTruth | None,
) -> EpisodeReport:
    """:func:`run_episode`, its ``out`` (if any) made and the earlier run's outputs set aside."""
    stepped = robot_moves(world)
    moves = move_keys(world)
    # The loader writes constant port values to the blackboard: clear it first, not after.
    py_trees.blackboard.Blackboard.clear()
    # Without a tree file, the shipped tree for the world's task.
    if tree_path is not None:
        root = load_tree(tree_path, main_tree_id=main_tree, run_keys=RUN_WRITES)
    else:
        root = default_tree(task_steps(world), world.tree_path())
    lib = library if library is not None else load_library(world)
    with SimWorld(world, gui=gui, truth=truth) as sim:
        recorder = MoveRecorder(sim, moves, stepped, 1.0 / world.sim.control_hz)
        hooks: list[Callable[[py_trees.trees.BehaviourTree], Any]] = [
            lambda tree: tree.add_post_tick_handler(recorder)
        ]
        log: RunLog | None = None
        btlog: BtLog | None = None
        publisher: Any = None
        anim: Animation | None = None
        if out is not None:
            log = RunLog(out / "run.jsonl", clock=sim.time)
            btlog = BtLog(out / "run.btlog", root, clock=sim.time)  # the same changes, for Groot2
            log.add_status_listener(btlog.record)
            if groot_port is not None:
                from planner.groot_publisher import GrootPublisher

                try:
                    publisher = GrootPublisher(btlog.tree, groot_port)
                except Exception:
                    log.close()
                    btlog.close()
                    raise
                log.add_status_listener(publisher.record)
            hooks.append(log.attach)
            if animation:
                table = world.table.size
                anim = Animation(
                    sim.scene.client,
                    world.objects[0].pose.position,
                    distance=1.6 * float(np.hypot(table[0], table[1])),
                    heading_deg=world.robot.base.rpy_deg[2],
                )
        last = [""]

        def on_tick(tree: py_trees.trees.BehaviourTree) -> None:
            if anim is not None:
                anim.maybe_capture(sim.time())
            tip = progress_node(tree) if progress is not None else None
            if progress is not None and tip is not None and tip.name != last[0]:
                last[0] = tip.name
                progress(sim.time(), readable(tip.name), readable(tip.feedback_message))

        try:
            result = run_tree(
                root,
                sim,
                lib,
                1.0 / world.sim.control_hz,
                world.sim.max_sim_time_s,
                {TASK_OBJECT_KEY: world.task[0].object},
                on_tick=on_tick,
                attach=tuple(hooks),
                max_wall_time=world.sim.max_wall_time_s,
            )
        finally:
            if log is not None:
                log.close()
            if btlog is not None:
                btlog.close()
            if publisher is not None:
                publisher.close()
        objects = [name for name, _ in recorder.finals]
        errors_m, errors_deg = recorder.column("error_m"), recorder.column("error_deg")
        moved, standing = recorder.moved_since_placed(), recorder.standing_moved()
        ok, failure = judge(
            result,
            sim,
            objects,
            errors_m,
            errors_deg,
            moved,
            standing,
            [why for name in dict.fromkeys(objects) if (why := off_the_table(sim, name))],
        )
        trays = tray_verdicts(sim.scene.spec.objects, sim.watched, recorder.grip)
        tray_failure = next((v.failure for v in trays if not v.ok), "")
        if ok and tray_failure:
            ok, failure = False, tray_failure
        inserted = insertion_verdict(sim)
        if inserted is not None and ok and not inserted.ok:
            ok, failure = False, inserted.reason
        report = EpisodeReport(
            ok,
            result.status.value,
            result.reason,
            errors_m,
            errors_deg,
            sim.safety.min_obstacle_distance_m,
            dict(sim.safety.obstacle_contacts),
            sim.safety.arm_contacts,
            sim.safety.dropped,
            result.sim_time,
            result.wall_time,
            failure,
            compositions=recorder.column("composition"),
            placement_objects=objects,
            skills=recorder.column("skill"),
        )
        report.physics_wall_s = sim.scene.physics_wall_s
        report.control_wall_s = sim.scene.control_wall_s
        report.watch_wall_s = sim.watch_wall_s()
        report.disturbances = [a.summary() for a in sim.scene.disturbances.applied()]
        report.grip = recorder.grip.metrics(HELD_FORCE_N)
        report.forearm_contacts = dict(sim.safety.forearm_contacts)
        report.min_forearm_distance_m = sim.safety.min_forearm_distance_m
        report.table_contacts = dict(sim.safety.table_contacts)
        report.tray = [v.summary() for v in trays]
        report.slid = recorder.slid()
        report.knocked = knocked_away(moved, standing)
        if inserted is not None:
            report.insertion = inserted.figures
        if out is not None:
            if log is not None and log.error is not None:
                report.output_errors.append(log.error)
            else:
                report.outputs["run_log"] = str(out / "run.jsonl")
            report.outputs["groot_log"] = str(out / "run.btlog")
            title = f"{world.name}: {'success' if ok else 'failure: ' + failure}"
            # The verdict is made: a figure that cannot be written costs that figure alone.
            try:
                report.outputs["trajectories"] = str(
                    trajectory_figure(recorder.traces(lib), out / "trajectories.png", title)
                )
            except OSError as err:
                report.output_errors.append(f"{out / 'trajectories.png'}: {err.strerror or err}")
            if anim is not None:
                try:
                    gif = anim.save_gif(out / "animation.gif")
                    if gif is not None:
                        report.outputs["animation"] = str(gif)
                except OSError as err:
                    report.output_errors.append(f"{out / 'animation.gif'}: {err.strerror or err}")
            try:
                with atomic_open(out / "tree.svg") as handle:
                    handle.write(render_tree(root, "svg"))
                report.outputs["tree"] = str(out / "tree.svg")
            except OSError as err:
                report.output_errors.append(f"{out / 'tree.svg'}: {err.strerror or err}")
    return report
