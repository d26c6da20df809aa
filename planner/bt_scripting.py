"""BT.CPP's script nodes (``Script``, ``ScriptCondition``, ``Precondition``) and the
pre/post-condition attributes every node may carry, run with :mod:`planner.bt_script`.

Keys in a script name entries of the node's blackboard namespace (``x`` in the main tree is
``/x``, in a subtree named ``sub`` it is ``/sub/x``); ``@x`` is always the root's ``/x``.
A script that fails at run time makes the node FAILURE, the reason in ``feedback_message``.
Enum names registered by the host (:mod:`planner.script_enums`) read as their integers.

Conditions (BT.CPP ``TreeNode::executeTick``): before a tick of a node that is not RUNNING,
``_failureIf`` (true: FAILURE), ``_successIf`` (SUCCESS), ``_skipIf`` (SKIPPED) and
``_while`` (false: SKIPPED) are checked in that order, and the node is not ticked if one
decides; while it is RUNNING only ``_while`` is checked, and a false one halts it. After a
tick that ends in SUCCESS ``_onSuccess`` runs, after FAILURE ``_onFailure``, after either
``_post``; ``_onHalted`` runs when a RUNNING node is halted. SKIPPED is given to py_trees as
:func:`planner.bt_decorators.skipped_status`.
"""

from __future__ import annotations

import uuid
from collections.abc import Iterator, Mapping
from typing import Any

import py_trees
from py_trees.blackboard import ActivityItem, ActivityType, Blackboard
from py_trees.common import Status
from py_trees.ports import PortInformation

from planner.bt_decorators import mark_ticked, skipped_status
from planner.bt_leaves import StringPorts
from planner.bt_script import Script, ScriptRuntimeError, parse_script, truthy
from planner.script_enums import script_enum
from planner.tree_bindings import Binding, subtree_bindings

__all__ = ["BUILTIN_SCRIPT_NODES", "BlackboardEnv", "install_conditions"]

Behaviour = py_trees.behaviour.Behaviour
#: The client id the scripts' writes carry in the blackboard's activity stream.
_SCRIPTS = uuid.uuid5(uuid.NAMESPACE_URL, "duet:bt-scripts")


class BlackboardEnv:
    """A :class:`planner.bt_script.ScriptEnv` over py_trees' blackboard at ``namespace``.

    ``remap`` is the table of the subtree instance the script runs in
    (:func:`planner.tree_bindings.subtree_bindings`): a port given ``{parent_key}`` reads and
    writes the caller's key, as in BT.CPP; a port given a literal reads it until the script
    writes its own value, which stays in the subtree.
    """

    def __init__(
        self, namespace: str = "/", remap: Mapping[str, Binding] | None = None, writer: str = ""
    ) -> None:
        self.namespace = namespace or "/"
        self.remap: Mapping[str, Binding] = remap or {}
        #: The node whose script writes, as the blackboard's activity stream names a client.
        self.writer = writer

    def key(self, key: str) -> str:
        """The absolute blackboard key a script key names."""
        if key.startswith("@"):
            return "/" + key[1:]
        bound = self.remap.get(key)
        if bound is not None and bound.key is not None:
            return bound.key
        return Blackboard.absolute_name(self.namespace, key)

    def _literal(self, key: str) -> str | None:
        bound = None if key.startswith("@") else self.remap.get(key)
        return bound.literal if bound is not None else None

    def read(self, key: str) -> Any:
        try:
            return Blackboard.get(self.key(key))
        except KeyError:
            literal = self._literal(key)
            if literal is None:
                raise
            return literal

    def write(self, key: str, value: Any) -> None:
        """Write the key, into the blackboard's activity stream too where one is kept (the run
        log records every write from it, as a client's write is recorded)."""
        absolute = self.key(key)
        stream = Blackboard.activity_stream
        if stream is not None:
            before = Blackboard.storage.get(absolute)
            stream.push(
                ActivityItem(
                    key=absolute,
                    client_name=self.writer,
                    client_id=_SCRIPTS,
                    activity_type=(
                        ActivityType.WRITE
                        if absolute in Blackboard.storage
                        else ActivityType.INITIALISED
                    ).value,
                    previous_value=before,
                    current_value=value,
                )
            )
        Blackboard.set(absolute, value)

    def exists(self, key: str) -> bool:
        return Blackboard.exists(self.key(key)) or self._literal(key) is not None

    def enum(self, name: str) -> int | None:
        return script_enum(name)


def run_script(
    script: Script, namespace: str, remap: Mapping[str, Binding] | None = None, writer: str = ""
) -> tuple[Any, str]:
    """Evaluate as node ``writer``; return (value, "") or (None, the reason it failed)."""
    try:
        return script.evaluate(BlackboardEnv(namespace, remap, writer)), ""
    except (ScriptRuntimeError, KeyError) as exc:
        return None, f"script {script.source!r}: {exc}"


def _namespace(node: Behaviour) -> str:
    return str(getattr(node, "_subtree_namespace", "/") or "/")


def _run(node: Behaviour, script: Script) -> tuple[Any, str]:
    """Run a script node's script in its subtree instance (namespace and table)."""
    return run_script(script, _namespace(node), getattr(node, "script_remap", None), node.name)


class ScriptNode(StringPorts, py_trees.behaviour.Behaviour, register=False):
    """BT.CPP ``Script code="..."``: run the script, SUCCESS (FAILURE if it cannot run)."""

    INPUT_PORTS: dict[str, PortInformation] = {}
    OUTPUT_PORTS: dict[str, PortInformation] = {}

    def __init__(self, name: str, code: str, **kwargs: Any) -> None:
        super().__init__(name=name, **kwargs)
        self.script = parse_script(code)
        #: The subtree instance's table (set by :func:`attach_conditions`).
        self.script_remap: Mapping[str, Binding] = {}

    def update(self) -> Status:
        """Run it."""
        _, error = _run(self, self.script)
        self.feedback_message = error
        return Status.FAILURE if error else Status.SUCCESS


class ScriptCondition(ScriptNode, register=False):
    """BT.CPP ``ScriptCondition code="..."``: SUCCESS when the script is true, else FAILURE."""

    def update(self) -> Status:
        """Evaluate and test it."""
        value, error = _run(self, self.script)
        if not error:
            try:
                return Status.SUCCESS if truthy(value) else Status.FAILURE
            except ScriptRuntimeError as exc:
                error = f"script {self.script.source!r}: {exc}"
        self.feedback_message = error
        return Status.FAILURE


class Precondition(StringPorts, py_trees.decorators.Decorator, register=False):
    """BT.CPP ``Precondition if="..." else="FAILURE"``: when entered, tick the child if the
    script is true, else return ``else`` (SUCCESS, FAILURE or RUNNING) without ticking it.
    While the child runs, the script is not checked again. (The reader names the attributes
    ``condition`` and ``otherwise``.)"""

    INPUT_PORTS: dict[str, PortInformation] = {}
    OUTPUT_PORTS: dict[str, PortInformation] = {}

    def __init__(
        self, name: str, child: Behaviour, condition: str, otherwise: str = "FAILURE", **kw: Any
    ) -> None:
        super().__init__(name=name, child=child, **kw)
        self.script = parse_script(condition)
        self.script_remap: Mapping[str, Binding] = {}
        if otherwise not in ("SUCCESS", "FAILURE", "RUNNING"):
            raise ValueError(f"{name}: else: expected SUCCESS, FAILURE or RUNNING, got {otherwise}")
        self.otherwise = Status[otherwise]

    def tick(self) -> Iterator[Behaviour]:
        """Check the script when entered, then pass the child's ticks through."""
        if self.status != Status.RUNNING:
            value, error = _run(self, self.script)
            if not error:
                try:
                    passed = truthy(value)
                except ScriptRuntimeError as exc:
                    error = str(exc)
            if error or not passed:
                self.feedback_message = error
                self.status = Status.FAILURE if error else self.otherwise
                yield self
                return
        yield from super().tick()

    def update(self) -> Status:
        """Reflect the child."""
        return self.decorated.status


#: BT.CPP tag -> class.
BUILTIN_SCRIPT_NODES: dict[str, type[Behaviour]] = {
    "Script": ScriptNode,
    "ScriptCondition": ScriptCondition,
    "Precondition": Precondition,
}
_SKIP = "skip"


def install_conditions(
    node: Behaviour,
    conditions: dict[str, Script],
    namespace: str,
    remap: Mapping[str, Binding] | None = None,
) -> None:
    """Give ``node`` BT.CPP's pre/post conditions (see the module's notes), in place."""
    if "_skipIf" in conditions or "_while" in conditions:
        node.bt_can_skip = True  # type: ignore[attr-defined]  # see propagate_skips
    original_tick = node.tick
    original_stop = node.stop

    def run(attr: str) -> tuple[Any, str]:
        return run_script(conditions[attr], namespace, remap, f"{node.name} {attr}")

    def check(attr: str) -> tuple[bool, str]:
        value, error = run(attr)
        if error:
            return False, error
        try:
            return truthy(value), ""
        except ScriptRuntimeError as exc:
            return False, f"{attr}: {exc}"

    def pre() -> tuple[Status | str | None, str]:
        if node.status == Status.RUNNING:
            if "_while" in conditions:
                ok, error = check("_while")
                if error:
                    return Status.FAILURE, error
                if not ok:
                    node.stop(Status.INVALID)
                    return _SKIP, ""
            return None, ""
        for attr, outcome in (
            ("_failureIf", Status.FAILURE),
            ("_successIf", Status.SUCCESS),
            ("_skipIf", _SKIP),
        ):
            if attr in conditions:
                ok, error = check(attr)
                if error:
                    return Status.FAILURE, error
                if ok:
                    return outcome, ""
        if "_while" in conditions:
            ok, error = check("_while")
            if error or not ok:
                return (Status.FAILURE, error) if error else (_SKIP, "")
        return None, ""

    def post(status: Status) -> None:
        attrs = {Status.SUCCESS: "_onSuccess", Status.FAILURE: "_onFailure"}
        if status not in attrs:
            return  # RUNNING: not yet done
        for attr in (attrs[status], "_post"):
            if attr in conditions:
                _, error = run(attr)
                if error:
                    node.feedback_message = error

    def tick() -> Iterator[Behaviour]:
        outcome, error = pre()
        if outcome != _SKIP:
            mark_ticked(node)
        if outcome is None:
            # Run before the node hands back its own status: a parent stops iterating at it
            # (a Fallback moves on to its next child, which may read what _onFailure wrote).
            for ticked in original_tick():
                if ticked is node:
                    post(node.status)
                yield ticked
            return
        if outcome == _SKIP:
            node.status = skipped_status(node)
        else:
            assert isinstance(outcome, Status)
            node.status = outcome
            node.feedback_message = error
            post(outcome)
        yield node

    def stop(new_status: Status = Status.INVALID) -> None:
        was_running = node.status == Status.RUNNING
        original_stop(new_status)
        if new_status == Status.INVALID and was_running and "_onHalted" in conditions:
            run("_onHalted")

    setattr(node, "tick", tick)  # noqa: B010 - per instance: the node's class is the user's
    setattr(node, "stop", stop)  # noqa: B010


def attach_conditions(
    elem: Any,
    node: Behaviour,
    trees: dict[str, Any],
    namespace: str,
    remap: Mapping[str, Binding] | None = None,
) -> None:
    """Walk a built tree beside the elements it was built from (one node per element, a
    ``<SubTree>`` standing for its tree's root): install each element's conditions, and give
    each script node its subtree instance's table (``script_remap``)."""
    table: Mapping[str, Binding] = remap or {}
    while elem.tag in ("SubTree", "BehaviorTree"):
        if elem.tag == "SubTree":
            ports = [n for n in node.iterate() if hasattr(n, "_subtree_namespace")]
            inner = _namespace(ports[0]) if ports else namespace
            # The subtree's own conditions apply to its root node, in the caller's instance.
            conditions = getattr(elem, "conditions", {})
            if conditions:
                install_conditions(node, conditions, namespace, table)
            tree = trees[elem.attrib["ID"]]
            table = subtree_bindings(elem, tree, namespace, table)
            elem, namespace = tree, inner
        else:
            elem = next(iter(elem))
    if isinstance(node, ScriptNode | Precondition):
        node.script_remap = table
    conditions = getattr(elem, "conditions", {})
    if conditions:
        install_conditions(
            node,
            conditions,
            _namespace(node) if hasattr(node, "_subtree_namespace") else namespace,
            table,
        )
    for child_elem, child in zip(list(elem), node.children, strict=False):
        attach_conditions(child_elem, child, trees, namespace, table)
