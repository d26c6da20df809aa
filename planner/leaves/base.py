"""What every robot leaf shares: the world port and skill library from ``setup()``."""

from __future__ import annotations

import functools
import inspect
import numbers
import re
import traceback
from collections.abc import Callable, Sequence
from typing import Any, ClassVar

import numpy as np
import py_trees
from py_trees.common import Status
from py_trees.ports import BehaviourWithPorts, NoDataAvailable, PortInformation
from py_trees.ports_utils import NOOP_LOGGER, LogLevel

from affordances import SemanticAction
from planner.bt_leaves import StringPorts
from planner.composition import MovePlan, compose_move, squeeze_force
from planner.leaves.set_down import table_found_dz
from planner.port import Move, WorldPort
from planner.runner import readable
from planner.tree_problems import LeafCodeError
from skills.library import SkillLibrary

#: Control period used when ``setup()`` is not given one, s.
DEFAULT_CONTROL_DT = 1.0 / 60.0
#: Squeeze force per palm a grasp reaches and a move is composed with, unless the plan's hold
#: skill asks for more, N; capped at the robot's rated steady squeeze. The reasoner's need
#: holds the weight; this margin also holds the box about the grip axis, where only the palms'
#: torsional friction resists: with 15 N, turned carries with a wrist near its limit let the
#: box pitch in the grip and drop (trials 24, 86, 99 of the default world's campaign).
SQUEEZE_FORCE_N = 25.0
#: What a leaf meeting an impossible value raises: a name the world does not have, a number
#: out of range, nothing on a port. The leaf fails with it as its feedback, so the tree's
#: fallbacks (and the run's verdict) see a failure instead of the run ending in a traceback.
IMPOSSIBLE_VALUE_ERRORS: tuple[type[Exception], ...] = (
    LookupError,
    ValueError,
    TypeError,
    ArithmeticError,
    NoDataAvailable,
)


#: The blackboard key a py_trees "has no data available" message names.
_MAPPED_TO = re.compile(r"\(mapped to '([^']+)'\) has no data available")


def _writers(leaf: py_trees.behaviour.Behaviour, key: str) -> list[str]:
    """``type.port`` of every node of ``leaf``'s tree with an output port writing blackboard
    ``key``, in tree order."""
    root = leaf
    while root.parent is not None:
        root = root.parent
    found = []
    for node in root.iterate():
        outputs = getattr(type(node), "output_ports", None)
        client = getattr(node, "blackboard_client", None)
        if outputs is None or client is None:
            continue
        for port in outputs():
            absolute = client.absolute_name(port)
            if client.remappings.get(absolute, absolute) == key:
                found.append(f"{type(node).__name__}.{port}")
    return found


def _no_data_hint(leaf: py_trees.behaviour.Behaviour, err: Exception) -> str:
    """For an input port with nothing on it, which nodes of the tree write its key (none have
    yet), so a tree's author sees which leaf had to run first."""
    found = _MAPPED_TO.search(str(err))
    if found is None:
        return ""
    counts: dict[str, int] = {}
    for writer in _writers(leaf, found.group(1)):
        counts[writer] = counts.get(writer, 0) + 1
    if not counts:
        return f"; no node of the tree writes {found.group(1)}"
    named = ", ".join(w if n == 1 else f"{w} ({n} of them)" for w, n in counts.items())
    return f"; written by {named} in this tree, none of which has yet"


#: The packages whose leaves are Duet's own: an error in them is Duet's bug, a traceback.
OWN_PACKAGES = frozenset({"planner", "skills", "worlds", "experiment", "affordances"})


def _user_leaf(leaf: WorldLeaf) -> bool:
    return type(leaf).__module__.split(".")[0] not in OWN_PACKAGES


def _code_error(leaf: WorldLeaf, hook: str, err: Exception) -> LeafCodeError:
    """What a user's leaf's bug says: where in its file it raised, which leaf, what."""
    frames = traceback.extract_tb(err.__traceback__)
    source = inspect.getsourcefile(type(leaf)) or ""
    own = [f for f in frames if f.filename == source] or frames[-1:]
    where = f"{own[-1].filename}:{own[-1].lineno}: " if own else ""
    kind = type(leaf).__name__
    return LeafCodeError(
        f"{where}leaf '{readable(leaf.name)}' ({kind}) raised {type(err).__name__} in {hook}(): "
        f"{err}; a bug in the leaf's code (its own failures are self.fail(...))"
    )


def _raise_if_user_bug(leaf: WorldLeaf, hook: str, err: Exception) -> None:
    """Raise the :class:`LeafCodeError` naming ``err`` when it is a bug in a user's leaf's
    ``hook``; return (for the caller to re-raise it) when it is Duet's own leaf's, or already
    named (a user's leaf's ``super()`` call that met the bug first)."""
    if _user_leaf(leaf) and not isinstance(err, LeafCodeError):
        raise _code_error(leaf, hook, err) from err


def _failing_softly(hook: Callable[..., Any], name: str) -> Callable[..., Any]:
    """``hook`` (a leaf's ``initialise`` or ``update``), failing the leaf on an impossible value;
    a user's leaf's other errors, and an ``update`` that returns no status, are a
    :class:`LeafCodeError` naming it."""

    @functools.wraps(hook)
    def guarded(self: WorldLeaf) -> Any:
        if name == "update" and self._impossible is not None:
            message, self._impossible = self._impossible, None
            return self.fail(message)
        try:
            result = hook(self)
        except IMPOSSIBLE_VALUE_ERRORS as err:
            if isinstance(err, OutputTypeError) and _user_leaf(self):
                raise _code_error(self, name, err) from err  # its own value, not the world's
            hint = _no_data_hint(self, err) if isinstance(err, NoDataAvailable) else ""
            text = str(err).rstrip(".") if hint else str(err)
            message = f"cannot {name}: {type(err).__name__}: {text}{hint}"
            if name == "update":
                return self.fail(message)
            self._impossible = message  # the tick's update reports it
            return None
        except Exception as err:
            _raise_if_user_bug(self, name, err)
            raise
        if name == "update" and not isinstance(result, Status):
            where = inspect.getsourcefile(type(self)) or type(self).__module__
            raise LeafCodeError(
                f"{where}: leaf '{readable(self.name)}' ({type(self).__name__}) update() returned "
                f"{result!r}: expected a py_trees Status (SUCCESS, FAILURE or RUNNING; "
                "return self.succeed(...), self.fail(...) or self.running(...))"
            )
        return result

    return guarded


def _naming_bugs(hook: Callable[..., Any], name: str) -> Callable[..., Any]:
    """``hook`` (a leaf's ``setup`` or ``terminate``), a user's leaf's error in it a
    :class:`LeafCodeError` naming it (these hooks return nothing a leaf could fail with)."""

    @functools.wraps(hook)
    def guarded(self: WorldLeaf, *args: Any, **kwargs: Any) -> Any:
        try:
            return hook(self, *args, **kwargs)
        except Exception as err:
            _raise_if_user_bug(self, name, err)
            raise

    return guarded


class OutputTypeError(TypeError):
    """A leaf wrote a value its output port's type does not take: the leaf's own bug (a user's
    leaf's stops the run naming its line), not an impossible value met in the world."""


def as_port_number(value: Any, data_type: Any) -> Any:
    """``value`` as a ``bool``, ``int`` or ``float`` port's own kind where it is a number that
    converts without loss (``np.True_`` to True, ``np.float32`` or an ``int`` to float,
    ``np.int64`` or 3.0 to 3); anything else as it is."""
    if isinstance(value, np.bool_):
        return bool(value)  # then as a Python bool: a bool port's, or an int's (py_trees')
    if data_type not in (int, float) or isinstance(value, bool):
        return value
    if not isinstance(value, numbers.Real) or type(value) is data_type:
        return value
    try:
        if data_type is float:
            number = float(value)
            # An integer is taken only where the float holds it exactly (not 2**53 + 1).
            lossless = not isinstance(value, numbers.Integral) or int(number) == int(value)
            return number if lossless else value
        if isinstance(value, numbers.Integral):
            return int(value)
        number = float(value)
        return int(number) if number.is_integer() else value
    except OverflowError:  # 10**400: no float; refused as of another type
        return value


class WorldLeaf(StringPorts, BehaviourWithPorts):
    """A leaf that talks to the world through :class:`~planner.port.WorldPort`.

    A string on the blackboard is read as its port's type, as BT.CPP reads it
    (``SetBlackboard value="0.05"`` feeding ``standoff_m="{standoff}"``).

    ``__init__`` only configures, so a tree builds and renders offline; ``setup(world=...,
    library=..., control_dt=...)`` connects it. A leaf used before ``setup`` fails with an
    explanation rather than an exception.

    ``WORLD_ROLES`` names the roles of the port (:mod:`planner.port`) a leaf uses; a test
    ticks each leaf through :class:`planner.testing.RoleView`, which offers those alone.
    """

    NODE_TYPE: ClassVar[str] = "Action"
    #: The port's roles the leaf asks the world for (all of them unless a leaf says fewer).
    WORLD_ROLES: ClassVar[tuple[type, ...]] = (WorldPort,)

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        for hook in ("initialise", "update"):
            if hook in cls.__dict__:
                setattr(cls, hook, _failing_softly(cls.__dict__[hook], hook))
        for hook in ("setup", "terminate"):
            if hook in cls.__dict__:
                setattr(cls, hook, _naming_bugs(cls.__dict__[hook], hook))

    def __init__(self, name: str, **kwargs: Any) -> None:
        super().__init__(name=name, **kwargs)
        self._impossible: str | None = None
        self._world: WorldPort | None = None
        self._library: SkillLibrary | None = None
        self.control_dt = DEFAULT_CONTROL_DT

    def log(
        self, level: LogLevel, msg: str, return_only: bool = False, print_name: bool = True
    ) -> str:
        """py_trees' port log, its DEBUG lines skipped where nothing would show them (the
        XML parser's no-op logger, or py_trees' own above DEBUG).

        ``setup_ports`` logs every key it registers at DEBUG, each line formatted (the node's
        name stripped of its uuid by a regular expression) before the logger drops it: a
        fifth of building a seven-move tree. A DEBUG line sets no feedback message, so
        nothing but the dropped text is skipped."""
        quiet = self._ports_logger is NOOP_LOGGER or (
            isinstance(self._ports_logger, py_trees.logging.Logger)
            and py_trees.logging.level != py_trees.logging.Level.DEBUG
        )
        if level is LogLevel.DEBUG and not return_only and quiet:
            return ""
        return super().log(level, msg, return_only, print_name)

    def setup(self, **kwargs: Any) -> None:
        """Receive the world port (``world``), the skill library (``library``) and
        ``control_dt``."""
        world = kwargs.get("world")
        if world is not None:
            self._world = world
        library = kwargs.get("library")
        if library is not None:
            self._library = library
        self.control_dt = float(kwargs.get("control_dt", self.control_dt))

    @property
    def world(self) -> WorldPort:
        """The world port given to ``setup``."""
        if self._world is None:
            raise RuntimeError(f"{self.name}: expected setup(world=...) before ticking")
        return self._world

    @property
    def library(self) -> SkillLibrary:
        """The skill library given to ``setup``."""
        if self._library is None:
            raise RuntimeError(f"{self.name}: expected setup(library=...) before ticking")
        return self._library

    def optional_input(self, port: str) -> Any:
        """An optional input's value, or None when nothing is wired or written to it."""
        try:
            return self.get_input(port)
        except NoDataAvailable:
            return None

    def palm_squeeze_force(self, plan: SemanticAction | None) -> float:
        """The squeeze force per palm this leaf works with, N: the larger of ``plan``'s hold
        force and the ``force_n`` port, capped at the robot's rating
        (:func:`planner.composition.squeeze_force`)."""
        return squeeze_force(
            plan, float(self.get_input("force_n")), self.world.robot_capabilities().squeeze_force_n
        )

    def _set_output(self, port_name: str, value: Any) -> None:
        """As :meth:`PortsMixin._set_output`; a number is written as the port's kind where
        that loses nothing (a numpy scalar, an integer on a float port, an integral float on
        an integer port: BT.CPP's blackboard converts numbers so); a value of another type
        than the port's is an :class:`OutputTypeError` naming the port."""
        info = type(self).OUTPUT_PORTS.get(port_name)
        data_type = getattr(info, "data_type", None)
        try:
            value = as_port_number(value, data_type)
            super()._set_output(port_name, value)
        except TypeError as err:
            kind = getattr(data_type, "__name__", "the port's type")
            given = type(value)
            named = given.__name__ if given.__module__ == "builtins" else given.__qualname__
            module = "" if given.__module__ == "builtins" else f"{given.__module__}."
            raise OutputTypeError(
                f"output port '{port_name}': expected {kind}, got {module}{named} {value!r:.60}"
            ) from err

    def fail(self, message: str) -> Status:
        """Return FAILURE with ``message`` as the explanation."""
        self.feedback_message = message
        self.logger.debug(f"{self.name}: {message}")
        return Status.FAILURE

    def running(self, message: str) -> Status:
        """Return RUNNING with a progress message."""
        self.feedback_message = message
        return Status.RUNNING

    def succeed(self, message: str) -> Status:
        """Return SUCCESS with a message."""
        self.feedback_message = message
        return Status.SUCCESS

    def connected(self) -> str | None:
        """Why the leaf cannot run, or None when it has a world."""
        if self._world is None:
            return "not set up: expected setup(world=...)"
        return None

    def object_and_move(self) -> tuple[str, int] | str:
        """The ``object`` and ``move`` ports' values, or why the leaf cannot use them (not
        set up, or no such move of the object's task)."""
        if (why := self.connected()) is not None:
            return why
        name = self.get_input("object")
        index = int(self.get_input("move"))
        if (bad := self.bad_move_index(name, index)) is not None:
            return bad
        return name, index

    def bad_move_index(self, name: str, index: int) -> str | None:
        """Why ``index`` names no move of ``name``'s task (as the robot makes it), or None."""
        count = len(self.world.task_moves(name))
        if not 0 <= index < count:
            return f"move {index}: expected an index below {count}"
        return None


def move_label(moves: Sequence[Move], name: str, index: int) -> str:
    """Move ``index`` of object ``name``'s ``moves`` (its task as the robot makes it) as the run's
    summary counts it: ``parcel move 3`` for the world file's third move, with ``, step 1 of
    2`` for a step of a turn made in several grasps; ``move 2`` for a move no world file
    listed."""
    task_move = moves[index].task_move
    if task_move is None:
        return f"move {index}"
    steps = [i for i, m in enumerate(moves) if m.task_move == task_move]
    label = f"{name} move {task_move + 1}"
    if len(steps) > 1:
        label += f", step {steps.index(index) + 1} of {len(steps)}"
    return label


def status_is_halt(new_status: Status) -> bool:
    """A parent preempted the leaf (``terminate(INVALID)``)."""
    return new_status == py_trees.common.Status.INVALID


def composition_ports() -> dict[str, PortInformation]:
    """The ports that choose a transport composition, shared by Transport and PathClear."""
    return {
        "force_n": PortInformation(
            float,
            required=False,
            default_value=SQUEEZE_FORCE_N,
            description="squeeze force per palm the move is composed with, N",
        ),
        "avoid_gain": PortInformation(
            float,
            required=False,
            default_value=1.0,
            description="multiplies the avoidance skills' weights",
        ),
        "transport_weight": PortInformation(
            float,
            required=False,
            default_value=1.0,
            description="multiplies the pick-and-place skill's weight (a lower carry)",
        ),
        "hold_gain": PortInformation(
            float,
            required=False,
            default_value=1.0,
            description="multiplies the grasp-maintenance skill's weight (0: carried without it)",
        ),
        "skill": PortInformation(
            str,
            required=False,
            description="name or label of the learnt skill to carry the object with; "
            "default: the world's move's skill, else the plan's transport skill",
        ),
        "above_fixture": PortInformation(
            bool,
            required=False,
            default_value=False,
            description="a move into a fixture ends above it, held, for Insert to lower it in",
        ),
    }


def composed_move(leaf: WorldLeaf, name: str, index: int) -> MovePlan:
    """Move ``index`` of ``name`` composed as ``leaf``'s ports ask: ``plan``, ``from_state``
    and :func:`composition_ports` (what PathClear checks and Transport runs).

    Raises
    ------
    SkillChoiceError
        If the ``skill`` asked for is not one the library can carry the object with.
    """
    plan = leaf.get_input("plan")
    return compose_move(
        plan,
        leaf.library,
        leaf.world,
        name,
        index,
        leaf.get_input("from_state"),
        leaf.palm_squeeze_force(plan),
        avoid_gain=float(leaf.get_input("avoid_gain")),
        transport_weight=float(leaf.get_input("transport_weight")),
        hold_gain=float(leaf.get_input("hold_gain")),
        skill=leaf.optional_input("skill"),
        above_fixture=bool(leaf.get_input("above_fixture")),
        table_dz=table_found_dz(leaf.world, name),
    )


def grasp_move_port() -> PortInformation:
    """The ``move`` port of the leaves that take hold of an object (Approach, Grasp)."""
    return PortInformation(
        int,
        required=False,
        default_value=-1,
        description="the task's move the grasp is for (its turn chooses the faces); "
        "-1: the faces nearest the robot's y axis",
    )


class MotionLeaf(WorldLeaf):
    """A leaf that moves the arms: halting it (a parent's preemption) stops them.

    ``terminate(INVALID)`` commands both palms to hold their last targets with zero twist, so
    a Timeout, a Selector switching branch or the runner's time limit never leaves the arms
    moving on their own.
    """

    def terminate(self, new_status: Status) -> None:
        """Preempted: stop the arms."""
        if status_is_halt(new_status) and self._world is not None:
            self._world.hold_palms()
