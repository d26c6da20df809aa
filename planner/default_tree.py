"""The default tree: the shipped ``planner/trees/pick_and_place.xml``, the one source of it.

The file's structure, which every task's tree keeps::

    Task (main tree)                     Sequence "task": one PickAndPlace per task step
      SubTree PickAndPlace  object=...   select skills, grasp, the step's moves, release, retreat
        SubTree Move  move=<index>       hold or regrasp, choose a composition, AtGoal
          SubTree CarryIfClear ...       PathClear then Transport, per composition variant

As shipped, the main tree has one PickAndPlace, for the object named by ``{object}`` on the
blackboard, with the paper's three moves. For a world's task, :func:`task_xml` rewrites the
same document: the main tree gets one PickAndPlace instance per step of the task, in the
task's order, named after its object (``parcel``; a later step of the same object
``parcel_2``), with the object as a constant port, so that each instance has its own
blackboard keys (``/parcel/plan``, ``/parcel/state`` ...). Each instance runs its own copy of
the file's PickAndPlace (``PickAndPlace_<first>_<count>``) whose Move subtrees are the file's
Move instance repeated once per move of the step, with the object's move indices (a step that
follows another of the same object goes on from that one's last move). The moves keep the
file's names (``move_centre``, ``move_right``, ``move_left``) and further ones are
``move_<n>`` (from 1); a task move made in several (a turn the grip cannot make in one) is
one Move per step, ``move_left_step_1``, ``move_left_step_2``. Nothing of a tree is built in
code: subtrees, compositions, guards and timeouts are the file's.

To change what a step does (e.g. regrasp between moves), change the file's PickAndPlace or
Move subtree; to change what runs per move, the Move subtree. :class:`TaskStep` is the only
input: which object, how many moves, from which of its moves.
"""

from __future__ import annotations

import copy
import re
import xml.etree.ElementTree as ET
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from py_trees.behaviour import Behaviour

import planner.leaves  # noqa: F401  (registers the leaves the file uses)
from planner.loader import load_tree, load_tree_string
from planner.tree_dataflow import RUN_WRITES
from planner.tree_problems import TreeFileError, TreeProblem

__all__ = [
    "PICK_AND_PLACE_XML",
    "TaskStep",
    "default_tree",
    "pick_and_place_xml",
    "task_xml",
    "template_main_tree",
]

#: The shipped tree of the paper's task.
PICK_AND_PLACE_XML = Path(__file__).resolve().parent / "trees" / "pick_and_place.xml"

#: The file's per-object subtree and the per-move subtree it repeats.
_STEP_TREE, _MOVE_TREE = "PickAndPlace", "Move"
#: The object port of the file's PickAndPlace instance: read from the blackboard.
_FROM_BLACKBOARD = "{object}"


@dataclass(frozen=True)
class TaskStep:
    """One step of a task: ``moves`` moves of ``object``, from its move ``first_move``.

    Attributes
    ----------
    object : str
        The object's name, or ``"{object}"`` to read it from the blackboard key ``/object``.
    moves : int
        Number of moves, at least 1.
    first_move : int
        Index of the step's first move among the object's moves (``task_moves``), from 0.
    task_moves : tuple of int
        Per move, the index of the task's move (as the world file lists the object's moves) it
        is a step of (:attr:`planner.port.Move.task_move`): a turn the grip cannot make in one
        is several moves, each named after the task's move (``move_left_step_1``,
        ``move_left_step_2``). Empty: each move is a task move of its own.
    """

    object: str
    moves: int
    first_move: int = 0
    task_moves: tuple[int, ...] = ()

    def __post_init__(self) -> None:
        if self.moves < 1:
            raise ValueError(
                f"TaskStep {self.object!r}: expected at least 1 move, got {self.moves}"
            )
        if self.first_move < 0:
            raise ValueError(
                f"TaskStep {self.object!r}: expected first_move >= 0, got {self.first_move}"
            )
        if self.task_moves and len(self.task_moves) != self.moves:
            raise ValueError(
                f"TaskStep {self.object!r}: expected one task move per move ({self.moves}), "
                f"got {len(self.task_moves)}"
            )

    def move_names(self, names: Sequence[str]) -> list[str]:
        """Each move's node name: the task move's name in ``names`` (the template's, by task
        move index) or ``move_<n>`` (n from 1) beyond them, with ``_step_<k>`` (k from 1)
        where the task move is made in several."""
        tasks = self.task_moves or tuple(range(self.first_move, self.first_move + self.moves))
        out = []
        for i, task in enumerate(tasks):
            base = names[task] if task < len(names) else f"move_{task + 1}"
            steps = tasks.count(task)
            out.append(base if steps == 1 else f"{base}_step_{tasks[: i + 1].count(task)}")
        return out


def _template_problem(template: Path, message: str) -> TreeFileError:
    return TreeFileError(
        [TreeProblem(str(template), None, "", f"as a task's tree template: {message}")]
    )


def _shipped(
    template: Path = PICK_AND_PLACE_XML,
) -> tuple[ET.Element, ET.Element, ET.Element, ET.Element]:
    """The document, its main Sequence, its PickAndPlace instance and definition.

    Raises
    ------
    TreeFileError
        If ``template`` is not XML or lacks that structure (names what is missing).
    """
    try:
        root = ET.parse(template).getroot()
    except (ET.ParseError, OSError) as err:
        raise _template_problem(template, f"expected a readable XML file ({err})") from None
    main_id = root.get("main_tree_to_execute") or _main_by_structure(root)
    if main_id is not None:
        root.set("main_tree_to_execute", main_id)
    main = root.find(f"BehaviorTree[@ID='{main_id}']")
    sequence = main[0] if main is not None and len(main) else None
    if sequence is None or sequence.tag != "Sequence":
        raise _template_problem(
            template, "expected main_tree_to_execute naming a tree whose root is a Sequence"
        )
    instance = next((e for e in sequence if e.tag == "SubTree" and e.get("ID") == _STEP_TREE), None)
    definition = root.find(f"BehaviorTree[@ID='{_STEP_TREE}']")
    if instance is None or definition is None or not len(definition):
        raise _template_problem(
            template,
            f'expected a <BehaviorTree ID="{_STEP_TREE}"> and a <SubTree ID="{_STEP_TREE}"> '
            "in the main tree's Sequence",
        )
    if not any(e.tag == "SubTree" and e.get("ID") == _MOVE_TREE for e in definition[0]):
        raise _template_problem(
            template,
            f'expected the {_STEP_TREE} tree\'s root to hold <SubTree ID="{_MOVE_TREE}"> '
            "(one is made per move of the task)",
        )
    return root, sequence, instance, definition


def _main_by_structure(root: ET.Element) -> str | None:
    """In a template saved without ``main_tree_to_execute`` (Groot2 writes none), the one
    tree whose root Sequence holds ``<SubTree ID="PickAndPlace">``; None if not just one."""
    found = [
        bt.get("ID")
        for bt in root.findall("BehaviorTree")
        if len(bt)
        and bt[0].tag == "Sequence"
        and any(e.tag == "SubTree" and e.get("ID") == _STEP_TREE for e in bt[0])
    ]
    return found[0] if len(found) == 1 else None


def template_main_tree(template: Path) -> str | None:
    """The main tree of a world's tree template: its ``main_tree_to_execute``, or in a file
    saved by Groot2 without one, the one tree whose root Sequence holds the PickAndPlace
    subtree (None if the file cannot tell: the reader then says so)."""
    try:
        root = ET.parse(template).getroot()
    except (ET.ParseError, OSError):
        return None
    return root.get("main_tree_to_execute") or _main_by_structure(root)


def _with_moves(definition: ET.Element, tree_id: str, step: TaskStep) -> ET.Element:
    """A copy of the PickAndPlace definition running ``step``'s moves."""
    out = copy.deepcopy(definition)
    out.set("ID", tree_id)
    body = out[0]
    shipped = [e for e in body if e.tag == "SubTree" and e.get("ID") == _MOVE_TREE]
    names = [e.get("name") or "" for e in shipped]
    at = list(body).index(shipped[0])
    for element in shipped:
        body.remove(element)
    for i, name in enumerate(step.move_names(names)):
        index = step.first_move + i
        element = copy.deepcopy(shipped[0])
        element.set("name", name)
        element.set("move", str(index))
        body.insert(at + i, element)
    return out


def _instance_name(name: str, used: set[str]) -> str:
    """A node name (and blackboard namespace) for an object: identifier characters, unique."""
    base = re.sub(r"\W", "_", name) or "object"
    candidate, k = base, 1
    while candidate in used:
        k += 1
        candidate = f"{base}_{k}"
    used.add(candidate)
    return candidate


def task_xml(steps: Sequence[TaskStep], template: Path = PICK_AND_PLACE_XML) -> str:
    """The ``template`` document (default: the shipped one) running ``steps`` in order, as XML
    text (see the module's doc).

    Raises
    ------
    ValueError
        If ``steps`` is empty.
    TreeFileError
        If ``template`` lacks the shipped tree's structure.
    """
    if not steps:
        raise ValueError("task_xml: expected at least 1 task step, got none")
    root, sequence, instance, definition = _shipped(template)
    at = list(sequence).index(instance)
    sequence.remove(instance)
    root.remove(definition)
    defined: dict[tuple[int, int], str] = {}
    used: set[str] = set()
    for k, step in enumerate(steps):
        key = (step.first_move, step.moves)
        if key not in defined:
            defined[key] = f"{_STEP_TREE}_{step.first_move}_{step.moves}"
            root.append(_with_moves(definition, defined[key], step))
        element = copy.deepcopy(instance)
        element.set("ID", defined[key])
        if step.object == _FROM_BLACKBOARD:
            used.add(instance.get("name") or "")
        else:
            element.set("name", _instance_name(step.object, used))
        element.set("object", step.object)
        sequence.insert(at + k, element)
    return ET.tostring(root, encoding="unicode")


def pick_and_place_xml(moves: int) -> str:
    """The shipped document with ``moves`` moves of the blackboard's ``{object}``, as XML text.

    Raises
    ------
    ValueError
        If ``moves`` is below 1.
    """
    if moves < 1:
        raise ValueError(f"pick_and_place_xml: expected at least 1 move, got {moves}")
    return task_xml([TaskStep(_FROM_BLACKBOARD, moves)])


def default_tree(task: int | Sequence[TaskStep] = 3, template: Path | None = None) -> Behaviour:
    """The tree ``app.py run`` and ``trials`` run without ``--tree``.

    Parameters
    ----------
    task : int or sequence of TaskStep
        A number of moves of the blackboard's ``/object`` (3: the shipped file as it is), or
        a world's task, step by step (:func:`task_xml`).
    template : Path, optional
        A tree of the shipped one's structure to make the task of (a world's ``tree``);
        default the shipped ``planner/trees/pick_and_place.xml``.

    Returns
    -------
    Behaviour
        The root as loaded by :func:`planner.loader.load_tree`; not set up.
    """
    template = template or PICK_AND_PLACE_XML
    if isinstance(task, int):
        if task == 3 and template == PICK_AND_PLACE_XML:
            return load_tree(PICK_AND_PLACE_XML, run_keys=RUN_WRITES)
        return load_tree_string(
            task_xml([TaskStep(_FROM_BLACKBOARD, task)], template),
            source=f"{template} ({task} moves)",
        )
    steps = list(task)
    what = ", ".join(f"{s.object} {s.moves} move{'s' * (s.moves != 1)}" for s in steps)
    return load_tree_string(task_xml(steps, template), source=f"{template} (task: {what})")
