"""Before a run: the checks that need no simulation, so a task that cannot work fails at once.

:func:`preflight_problems` gathers the world's feasibility (:mod:`worlds.feasibility`: a grasp
the robot can make, goals on the table and within reach) and, with a tree, the tree's own checks
(:mod:`planner.validate`) and its moves against the world's task (:mod:`planner.tree_task`),
and, once those pass, that no obstacle appears where the arms hold the object
(:mod:`worlds.obstacle_holds`).
``app.py validate``, ``run`` and ``trials`` call it before anything is simulated.
"""

from __future__ import annotations

import os
import sys
from collections.abc import Sequence
from pathlib import Path

from planner.default_tree import PICK_AND_PLACE_XML, TaskStep, task_xml, template_main_tree
from planner.port import Move
from planner.tree_dataflow import RUN_WRITES
from planner.tree_objects import check_tree_objects
from planner.tree_problems import TreeFileError
from planner.tree_reading import (
    TreeDocument,
    describe,
    read_tree_document,
    source_file,
    source_line,
)
from planner.tree_task import check_tree_moves, tree_grasps
from planner.validate import validate_tree
from worlds.feasibility import feasibility_problems
from worlds.obstacle_holds import obstacle_hold_problems
from worlds.sim_world import task_moves
from worlds.spec import WorldSpec
from worlds.start_checks import start_pose_problems
from worlds.world_file import World, WorldFileError, load_world, world_spec, world_summary


def bound_object(world: World) -> str | None:
    """The object a tree's ``{object}`` ports name in a run: the task's first object, as
    :func:`experiment.episode.run_episode` writes it to ``/object``."""
    return world.task[0].object if world.task else None


def preflight_problems(
    world: World, world_file: str, tree: Path | None = None, main_tree: str | None = None
) -> list[str]:
    """Every problem found without simulating, one line each, each naming its file.

    Parameters
    ----------
    world : World
        The validated world.
    world_file : str
        The world file as the user named it, for the messages.
    tree : Path, optional
        The tree to run: checked itself, its moves against the world's task and its grasps
        against the objects. Without one, the default tree's grasps are used (its moves
        follow the world's task).
    main_tree : str, optional
        The ``<BehaviorTree ID>`` of ``tree`` to run instead of its ``main_tree_to_execute``.

    Returns
    -------
    list of str
        Empty when the run may start.
    """
    import planner.leaves  # noqa: F401  (registers the leaves a tree may use)

    if main_tree is not None and tree is None:
        # The task's tree is made from a template whose main tree is its structure: an ID
        # asked of it would be ignored without a word.
        return [
            f"--main-tree {main_tree}: expected with --tree (the file whose <BehaviorTree "
            f"ID> it names), got none: {world_file}'s task tree is made from "
            f"{'its own template' if world.tree is not None else 'the shipped one'}"
        ]
    # Without --tree, the world's own tree template (its ``tree``) or the shipped one.
    template = world.tree_path() if tree is None else None
    checked = tree if tree is not None else template
    # A template saved by Groot2 names no main tree: its structure does.
    template_main = template_main_tree(template) if template is not None else None
    if checked is not None:
        tree_problems = validate_tree(
            checked, main_tree_id=main_tree if tree else template_main, run_keys=RUN_WRITES
        )
        if tree_problems:
            return [str(p) for p in tree_problems]
    try:
        if template is not None:  # made into this task as a run would, for its structure
            task_xml([TaskStep(s.object, len(s.moves)) for s in world.task], template)
        if tree is not None:
            doc = read_tree_document(tree, main_tree_id=main_tree)
        else:
            doc = read_tree_document(template or PICK_AND_PLACE_XML, main_tree_id=template_main)
    except TreeFileError as err:
        return [str(p) for p in err.problems]
    lines = [p.format(world_file) for p in feasibility_problems(world, tree_grasps(doc))]
    if not lines:  # the robot where a run starts, then posed at goals found sound above
        lines = [p.format(world_file) for p in start_pose_problems(world)]
    if not lines:
        lines = [p.format(world_file) for p in obstacle_hold_problems(world)]
    if tree is not None:
        lines += tree_task_problems(world, doc)
    return lines + skill_problems(world, world_file, doc)


def tree_task_problems(world: World, doc: TreeDocument) -> list[str]:
    """One line per way a tree (``--tree``, run as written) does not fit the world's task:
    a move index the task lacks or a move it has that no Move makes, an object it names
    that the world lacks."""
    spec = world_spec(world)
    # The moves as the robot makes them (a turn its grip cannot make is several), which
    # is what a tree's move indices count.
    stepped = {step.object: task_moves(spec, step.object) for step in spec.task}
    moves = {name: len(made) for name, made in stepped.items()}
    notes = {name: steps_note(made) for name, made in stepped.items()}
    lines = [
        str(p)
        for p in check_tree_moves(
            doc, moves, bound_object(world), {k: v for k, v in notes.items() if v}
        )
    ]
    names = [o.name for o in world.objects]
    return (
        lines + [str(p) for p in check_tree_objects(doc, names)] + _inserts_into_nothing(spec, doc)
    )


def _inserts_into_nothing(spec: WorldSpec, doc: TreeDocument) -> list[str]:
    """A line per ``Insert`` of a tree run on a task none of whose moves goes into a fixture:
    it had validated, then failed at run time ("move 0 of 'tray' goes into no fixture")."""
    if any(m.fixture is not None for step in spec.task for m in step.moves):
        return []  # which moves an Insert runs on is the tree's data flow: run tells
    return [
        f"{source_file(elem, doc.file)}:{source_line(elem)}: {describe(elem)}: inserts into a "
        "fixture, but no move of the world's task goes into one (a move's `fixture:`)"
        for elem in doc.root.iter("Insert")
    ]


def steps_note(made: Sequence[Move]) -> str:
    """How the robot's moves of one object come from its world file's, where a turn the grip
    cannot make is several: ``"the world file's move 2 is made in 2 steps, 2 and 3"``; empty
    when each file move is one."""
    indices: dict[int, list[int]] = {}
    for k, move in enumerate(made):
        indices.setdefault(move.task_move if move.task_move is not None else k, []).append(k)
    split = [(m, ks) for m, ks in indices.items() if len(ks) > 1]
    return "; ".join(
        f"the world file's move {m} is made in {len(ks)} steps, "
        f"{', '.join(str(k) for k in ks[:-1])} and {ks[-1]}"
        for m, ks in split
    )


def skill_problems(world: World, world_file: str, doc: TreeDocument) -> list[str]:
    """One line per skill the world's library cannot carry a move with, named by a move's
    ``skill`` field, then by a node's literal ``skill`` port of the tree that runs (on the
    node, or on a ``<SubTree>`` feeding it: it had validated, and failed the run at its first
    carry). The library is read once: always when the world names a folder of its own (a
    damaged one had validated and then failed every trial of a campaign), else only when
    something names a skill (the default one is learnt, a cost a run pays anyway)."""
    from experiment.episode import load_library
    from planner.skill_choice import SkillChoiceError, transport_skill
    from planner.tree_dataflow import port_uses
    from skills.library import LibraryFileError

    named = {
        (f"{world_file}: task[{i}].moves[{j}].skill", move.skill): None
        for i, step in enumerate(world.task)
        for j, move in enumerate(step.moves)
        if move.skill is not None
    }
    for use in port_uses(doc):
        if use.port == "skill" and use.direction == "read" and use.binding.literal is not None:
            where = use.binding.origin if use.binding.origin is not None else use.elem
            node = f"{source_file(where, doc.file)}:{source_line(where)}: {describe(where)}"
            named[(f"{node}: port 'skill'", str(use.binding.literal))] = None
    if not named and world.skills.library == "default":
        return []
    try:
        library = load_library(world)
    except LibraryFileError as err:
        return [str(err)]
    problems = []
    for field, key in named:
        try:
            transport_skill(library, key)
        except SkillChoiceError as err:
            problems.append(f"{field}: {err}")
    return problems


def validate_cli(world_file: str, tree: str | None = None, main_tree: str | None = None) -> int:
    """``app.py validate WORLD [--tree T.xml]``: 0 and a summary, or 2 and one line per problem.

    Returns 1 on an internal error (message on stderr, never a traceback).
    """
    try:
        world = load_world(world_file)
        problems = preflight_problems(world, world_file, Path(tree) if tree else None, main_tree)
    except WorldFileError as err:
        print(err, file=sys.stderr)
        return 2
    except Exception as exc:  # the command line promises no tracebacks
        print(
            f"{world_file}: internal error while validating: {type(exc).__name__}: {exc}",
            file=sys.stderr,
        )
        return 1
    if problems:
        for line in problems:
            print(line, file=sys.stderr)
        return 2
    against = f"; tree {os.fspath(tree)} matches its task" if tree else ""
    print(f"{world_file}: ok: {world_summary(world)}{against}")
    return 0


__all__ = ["bound_object", "preflight_problems", "skill_problems", "validate_cli"]
