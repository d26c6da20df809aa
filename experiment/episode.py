"""One run of a world: build the scene, run the tree, judge it, write what it shows.

Used by ``app.py run`` (one episode with all its outputs) and ``app.py trials`` (many, lean).
A run succeeds only if the tree succeeds and every criterion of the paper's experiment holds:
each placement within 2 cm and 10 degrees of its goal, the parcel never dropped, no robot link
and no part of the parcel touching an obstacle (PyBullet contacts and FCL distance), and the
arms never touching each other.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import py_trees
from py_trees.common import Status

import planner.leaves  # noqa: F401  (registers the leaves for the XML loader)
from experiment.figures import Animation, MoveTrace, trajectory_figure
from planner.default_tree import default_tree
from planner.loader import load_tree
from planner.move_result import move_results
from planner.render import render_tree
from planner.runlog import RunLog
from planner.runner import RunResult, run_tree
from skills.default_library import DEMOS_DIR, build_default_library
from skills.demos.io import read_demo_csv
from skills.library import SkillLibrary
from worlds.sim_world import SimWorld, task_moves
from worlds.world_file import World, as_world_spec

PLACE_TOLERANCE_M = 0.02
PLACE_TOLERANCE_DEG = 10.0


@dataclass
class EpisodeReport:
    """Everything a run is judged on, JSON-ready via :meth:`summary`."""

    success: bool
    tree_status: str
    reason: str
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
    #: Per move, the composition that placed the object: ``{"transport_weight": w,
    #: "avoid_gain": g}`` of the Transport leaf that succeeded (its published
    #: :class:`planner.move_result.MoveResult`), or None if none did.
    compositions: list[dict[str, float] | None] = field(default_factory=list)

    def summary(self) -> dict[str, Any]:
        """Plain JSON-safe dictionary (infinite distances as None)."""
        d = self.min_obstacle_distance_m
        return {
            "success": self.success,
            "failure": self.failure,
            "tree_status": self.tree_status,
            "reason": self.reason,
            "placement_error_m": self.placement_error_m,
            "placement_error_deg": self.placement_error_deg,
            "min_obstacle_distance_m": None if math.isinf(d) else round(d, 5),
            "obstacle_contacts": self.obstacle_contacts,
            "arm_contacts": self.arm_contacts,
            "dropped": self.dropped,
            "sim_time_s": round(self.sim_time_s, 3),
            "wall_time_s": round(self.wall_time_s, 3),
            "compositions": self.compositions,
            "outputs": self.outputs,
        }


def load_library(world: World) -> SkillLibrary:
    """The world's skill library: the default one, or a folder (LibraryFileError if bad)."""
    if world.skills.library == "default":
        return build_default_library()
    return SkillLibrary.load(world.resolve_path(world.skills.library))


def judge(
    result: RunResult, sim: SimWorld, errors_m: list[float | None], errors_deg: list[float | None]
) -> tuple[bool, str]:
    """Success and the first failure reason, in the order the paper's criteria are listed."""
    s = sim.safety
    if s.dropped:
        return False, "dropped"
    if s.obstacle_contacts:
        return False, "obstacle contact: " + ", ".join(sorted(s.obstacle_contacts))
    if s.arm_contacts:
        return False, "arms touched"
    if not result.success:
        return False, f"tree {result.status.value.lower()}: {result.reason}"
    for i, (e, d) in enumerate(zip(errors_m, errors_deg, strict=True)):
        if e is None or d is None:
            return False, f"move {i + 1} not placed"
        if e > PLACE_TOLERANCE_M or d > PLACE_TOLERANCE_DEG:
            return False, f"move {i + 1} placed {e * 100:.1f} cm, {d:.1f} deg from its goal"
    return True, ""


class _Recorder:
    """Post-tick bookkeeping: object path per move and each move's placement error.

    It reads the moves' published results (:func:`planner.move_result.move_results`,
    written by the Transport leaves), not the leaves: while a move's latest result is RUNNING
    the object's position is sampled into that move's path; when it turns SUCCESS the move's
    placement error and composition are kept.
    """

    def __init__(self, sim: SimWorld, name: str, n_moves: int) -> None:
        self.sim, self.name = sim, name
        self.moves = sim.task_moves(name)
        self.paths: list[list[np.ndarray]] = [[] for _ in range(n_moves)]
        self.starts: list[np.ndarray | None] = [None] * n_moves
        self.obstacles: list[tuple[Any, ...]] = [() for _ in range(n_moves)]
        self.errors_m: list[float | None] = [None] * n_moves
        self.errors_deg: list[float | None] = [None] * n_moves
        self.compositions: list[dict[str, float] | None] = [None] * n_moves
        self.current: int | None = None
        self.tip_name = ""

    def __call__(self, tree: py_trees.trees.BehaviourTree) -> None:
        pose = self.sim.object_pose(self.name)
        # In move order, as a move that ends and the next that starts share a tick.
        for (obj, index), result in sorted(move_results().items(), key=lambda kv: kv[0][1]):
            if obj != self.name or not 0 <= index < len(self.moves):
                continue
            if result.status == Status.RUNNING:
                if self.starts[index] is None:
                    self.starts[index] = pose.position.copy()
                    self.obstacles[index] = self.sim.obstacles()
                self.paths[index].append(pose.position.copy())
                self.current = index
            elif result.status == Status.SUCCESS and self.current == index:
                assert result.placement_error_m is not None
                assert result.placement_error_rad is not None
                self.errors_m[index] = result.placement_error_m
                self.errors_deg[index] = float(np.degrees(result.placement_error_rad))
                self.paths[index].append(pose.position.copy())
                self.compositions[index] = {
                    "transport_weight": result.transport_weight,
                    "avoid_gain": result.avoid_gain,
                }
                self.current = None
        tip = tree.tip()
        self.tip_name = tip.name if tip is not None else ""

    def traces(self) -> list[MoveTrace]:
        """One trace per move of the world file, its steps' paths joined."""
        out: list[MoveTrace] = []
        first = 0
        for i, move in enumerate(self.moves):
            if not move.final:
                continue
            start = next((s for s in self.starts[first : i + 1] if s is not None), None)
            points = [p for k in range(first, i + 1) for p in self.paths[k]]
            path = np.array(points) if points else np.zeros((0, 3))
            out.append(
                MoveTrace(
                    len(out),
                    start if start is not None else move.goal.position,
                    move.goal.position,
                    path,
                    self.obstacles[first],
                )
            )
            first = i + 1
        return out


def run_episode(
    world: World,
    tree_path: Path | None = None,
    library: SkillLibrary | None = None,
    out: Path | None = None,
    animation: bool = True,
    progress: Callable[[float, str, str], None] | None = None,
    gui: bool = False,
) -> EpisodeReport:
    """Run the world's task once and judge it.

    Parameters
    ----------
    world : World
    tree_path : Path, optional
        Behaviour tree XML; default: :func:`planner.default_tree.default_tree` for the first
        task object's number of moves (``planner/trees/pick_and_place.xml`` for three).
    library : SkillLibrary, optional
        Default: the world's.
    out : Path, optional
        Folder for ``run.jsonl``, ``trajectories.png``, ``animation.gif`` and ``tree.svg``;
        None writes nothing.
    animation : bool
        Capture frames with the CPU renderer (slower).
    progress : callable (sim_time, leaf_name, feedback), optional
        Called when the running leaf changes.
    gui : bool
        Show PyBullet's window (needs a display; :class:`worlds.scene.NoDisplayError`).

    Raises
    ------
    planner.loader.TreeFileError, skills.library.LibraryFileError
        On bad input files (the caller turns them into exit code 2).
    """
    name = world.task[0].object
    # The moves as the robot makes them: a turn its grip cannot make is several moves.
    steps = task_moves(as_world_spec(world), name)
    n_moves = len(steps)
    # The loader writes constant port values to the blackboard: clear it first, not after.
    py_trees.blackboard.Blackboard.clear()
    # Without a tree file, the shipped tree (its Move subtree once per move of the task).
    root = load_tree(tree_path) if tree_path is not None else default_tree(n_moves)
    lib = library if library is not None else load_library(world)
    with SimWorld(world, name, gui=gui) as sim:
        recorder = _Recorder(sim, name, n_moves)
        hooks: list[Callable[[py_trees.trees.BehaviourTree], Any]] = [
            lambda tree: tree.add_post_tick_handler(recorder)
        ]
        log: RunLog | None = None
        anim: Animation | None = None
        if out is not None:
            out.mkdir(parents=True, exist_ok=True)
            log = RunLog(out / "run.jsonl", clock=sim.time)
            hooks.append(log.attach)
            if animation:
                table = world.table.size
                anim = Animation(
                    sim.scene.client,
                    world.objects[0].pose.position,
                    distance=1.6 * float(np.hypot(table[0], table[1])),
                )
        last = [""]

        def on_tick(tree: py_trees.trees.BehaviourTree) -> None:
            if anim is not None:
                anim.maybe_capture(sim.time())
            tip = tree.tip()
            if progress is not None and tip is not None and tip.name != last[0]:
                last[0] = tip.name
                progress(sim.time(), tip.name, tip.feedback_message)

        try:
            result = run_tree(
                root,
                sim,
                lib,
                1.0 / world.sim.control_hz,
                world.sim.max_sim_time_s,
                {"/object": name},
                on_tick=on_tick,
                attach=tuple(hooks),
            )
        finally:
            if log is not None:
                log.close()
        # Judged per move of the world file: on the last step of each.
        finals = [i for i, m in enumerate(steps) if m.final]
        errors_m = [recorder.errors_m[i] for i in finals]
        errors_deg = [recorder.errors_deg[i] for i in finals]
        ok, failure = judge(result, sim, errors_m, errors_deg)
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
            compositions=[recorder.compositions[i] for i in finals],
        )
        if out is not None:
            report.outputs["run_log"] = str(out / "run.jsonl")
            demo = read_demo_csv(DEMOS_DIR / "pick_place.csv").demonstration.positions
            title = f"{world.name}: {'success' if ok else 'failure: ' + failure}"
            report.outputs["trajectories"] = str(
                trajectory_figure(recorder.traces(), demo, out / "trajectories.png", title)
            )
            if anim is not None:
                gif = anim.save_gif(out / "animation.gif")
                if gif is not None:
                    report.outputs["animation"] = str(gif)
            (out / "tree.svg").write_text(render_tree(root, "svg"), encoding="utf-8")
            report.outputs["tree"] = str(out / "tree.svg")
    return report
