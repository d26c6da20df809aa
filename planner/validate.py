"""Check a behaviour tree file without building it: tags, ports, literals, subtrees, names.

A tree file is BehaviorTree.CPP v4 style XML. :func:`read_tree_document` reads it with the line
of every element, inlines ``<include>`` files and translates BT.CPP spellings (``Fallback``,
``RetryUntilSuccessful num_attempts=``, ``Timeout msec=`` ...) into the tags py_trees' parser
builds; :func:`check_tree_document` then finds every problem the parser (or a first tick) would
trip over, each with file, line, node and what was expected. :mod:`planner.loader` runs the
same two steps before it builds, so a tree that validates also loads.
"""

from __future__ import annotations

import difflib
import enum
import functools
import inspect
import os
import sys
import typing
import xml.etree.ElementTree as ET
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, get_args, get_origin
from xml.parsers import expat

import py_trees
from py_trees.parsers.behaviour_tree_xml import DECORATOR_NODES
from py_trees.ports import PortInformation, PortsMixin, get_ports_registry
from py_trees.ports_utils import convert_str_to_type

from planner.decorators import SimTimeout

__all__ = [
    "TreeDocument",
    "TreeFileError",
    "TreeProblem",
    "check_tree_document",
    "effective_registry",
    "read_tree_document",
    "read_tree_document_string",
    "tree_cli_validate",
    "validate_tree",
    "validate_tree_string",
]

#: Registry entries: a :class:`~py_trees.ports.PortsMixin` class or a ``functools.partial`` of one.
Registry = Mapping[str, Any]

COMPOSITES = ("Sequence", "Selector", "Parallel")
SUBTREE_TAGS = ("SubTree", "SubTreePlus")
#: Parallel policies the py_trees parser can build (``success_on_selected`` needs a child list).
PARALLEL_POLICIES = ("success_on_all", "success_on_one")
#: Constructor parameters the parser fills itself, never from an attribute.
_IMPLICIT_PARAMS = frozenset({"self", "name", "child", "children", "behaviour_class_name"})
#: Groot/BT.CPP bookkeeping attributes that carry no meaning for a run; dropped silently.
_IGNORED_ATTRIBUTES = frozenset({"_description", "_uid", "_fullpath"})
_BUILTIN_DECORATORS: dict[str, type[py_trees.decorators.Decorator]] = {
    cls.__name__: cls for cls in DECORATOR_NODES.values()
}


# --------------------------------------------------------------------------------------------
# Problems and errors
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class TreeProblem:
    """One thing wrong with a tree file.

    Attributes
    ----------
    file : str
        The file as given (or the ``source`` label of a string).
    line : int or None
        1-based line of the offending element; None for whole-file problems.
    node : str
        The element as written, e.g. ``<Grasp name="grip">``; empty for whole-file problems.
    message : str
        What is wrong and what was expected.
    column : int or None
        1-based column, for XML syntax errors only.
    """

    file: str
    line: int | None
    node: str
    message: str
    column: int | None = None

    def __str__(self) -> str:
        where = self.file
        if self.line is not None:
            where += f":{self.line}"
            if self.column is not None:
                where += f":{self.column}"
        return f"{where}: {self.node}: {self.message}" if self.node else f"{where}: {self.message}"


class TreeFileError(ValueError):
    """A tree file that cannot be loaded; ``str()`` gives one ``file:line: node: message`` per line.

    Parameters
    ----------
    problems : sequence of TreeProblem
        At least one problem.
    """

    def __init__(self, problems: list[TreeProblem] | tuple[TreeProblem, ...]) -> None:
        if not problems:
            raise ValueError("TreeFileError: expected at least one problem")
        self.problems: tuple[TreeProblem, ...] = tuple(problems)
        super().__init__("\n".join(str(p) for p in self.problems))


# --------------------------------------------------------------------------------------------
# Reading: expat with line numbers, includes, BT.CPP translation
# --------------------------------------------------------------------------------------------


class SourceElement(ET.Element):
    """An element that remembers where it was written.

    ``sourcefile`` and ``sourceline`` locate the start tag; ``source_tag`` and ``source_attrib``
    keep the spelling as written, before BT.CPP names are translated, for messages.
    """

    sourcefile: str
    sourceline: int
    source_tag: str
    source_attrib: dict[str, str]


def describe(elem: ET.Element) -> str:
    """Return the element as written for messages, e.g. ``<Grasp name="grip">``."""
    tag = getattr(elem, "source_tag", elem.tag)
    attrib = getattr(elem, "source_attrib", elem.attrib)
    parts = [tag]
    for key in ("ID", "name"):
        if key in attrib:
            parts.append(f'{key}="{attrib[key]}"')
    return "<" + " ".join(parts) + ">"


def _line(elem: ET.Element) -> int | None:
    return getattr(elem, "sourceline", None)


def _file(elem: ET.Element, default: str) -> str:
    return getattr(elem, "sourcefile", default)


def _parse_xml(data: bytes | str, source: str) -> SourceElement:
    """Parse XML text into :class:`SourceElement` s; raise TreeFileError on a syntax error."""
    parser = expat.ParserCreate()
    stack: list[SourceElement] = []
    document: list[SourceElement] = []

    def start(tag: str, attrib: dict[str, str]) -> None:
        elem = SourceElement(tag, attrib)
        elem.sourcefile = source
        elem.sourceline = parser.CurrentLineNumber
        elem.source_tag = tag
        elem.source_attrib = dict(attrib)
        if stack:
            stack[-1].append(elem)
        else:
            document.append(elem)
        stack.append(elem)

    def end(tag: str) -> None:
        stack.pop()

    parser.StartElementHandler = start
    parser.EndElementHandler = end
    try:
        parser.Parse(data, True)
    except expat.ExpatError as exc:
        message = expat.errors.messages.get(exc.code, str(exc)) if exc.code else str(exc)
        raise TreeFileError(
            [
                TreeProblem(
                    source,
                    exc.lineno,
                    "",
                    f"XML syntax error: {message}",
                    column=exc.offset + 1,
                )
            ]
        ) from None
    return document[0]


@dataclass
class TreeDocument:
    """A tree file read and translated, ready to check or build.

    Attributes
    ----------
    file : str
        The file as given, or the ``source`` label of a string.
    root : SourceElement
        The ``<root>`` element, includes inlined and BT.CPP spellings translated.
    main_tree_id : str or None
        The tree to run: ``main_tree_to_execute``, or the only ``<BehaviorTree>``.
    problems : list of TreeProblem
        Problems met while reading and translating.
    """

    file: str
    root: SourceElement
    main_tree_id: str | None
    problems: list[TreeProblem] = field(default_factory=list)

    def behaviour_trees(self) -> dict[str, ET.Element]:
        """Return ``{ID: <BehaviorTree> element}``; first definition wins."""
        index: dict[str, ET.Element] = {}
        for bt in self.root.findall("BehaviorTree"):
            bt_id = bt.attrib.get("ID")
            if bt_id is not None and bt_id not in index:
                index[bt_id] = bt
        return index


def read_tree_document(
    path: str | os.PathLike[str],
    registry: Registry | None = None,
    main_tree_id: str | None = None,
) -> TreeDocument:
    """Read a tree file: line numbers, includes inlined, BT.CPP spellings translated.

    Parameters
    ----------
    path : path-like
        The XML file.
    registry : mapping tag -> class, optional
        Leaf classes; default the py_trees ports registry (see :func:`effective_registry`).
    main_tree_id : str, optional
        The tree to run instead of ``main_tree_to_execute``.

    Raises
    ------
    TreeFileError
        When the file is missing, unreadable or not well-formed XML.
    """
    source = os.fspath(path)
    try:
        data = Path(source).read_bytes()
    except OSError as exc:
        raise TreeFileError(
            [TreeProblem(source, None, "", f"cannot read: {exc.strerror}")]
        ) from None
    return _read(data, source, os.path.dirname(os.path.abspath(source)), registry, main_tree_id)


def read_tree_document_string(
    text: str,
    source: str = "<string>",
    registry: Registry | None = None,
    main_tree_id: str | None = None,
) -> TreeDocument:
    """Read tree XML from a string (see :func:`read_tree_document`); includes resolve from cwd."""
    return _read(text, source, os.getcwd(), registry, main_tree_id)


def _read(
    data: bytes | str,
    source: str,
    base_dir: str,
    registry: Registry | None,
    main_tree_id: str | None = None,
) -> TreeDocument:
    root = _parse_xml(data, source)
    problems: list[TreeProblem] = []
    if root.tag != "root":
        problems.append(
            TreeProblem(
                source, root.sourceline, describe(root), "expected <root> as the document element"
            )
        )
    visited = {os.path.abspath(source)} if os.path.exists(source) else set()
    _inline_includes(root, base_dir, visited, problems)
    # Translate against the caller's registry only: a user-registered tag wins over a BT.CPP
    # spelling, but our own default Timeout still takes the BT.CPP ``msec`` spelling.
    user = get_ports_registry() if registry is None else registry
    for bt in root.findall("BehaviorTree"):
        for elem in bt.iter():
            if elem is not bt:
                _translate(elem, user, problems)
    main_id = main_tree_id or root.attrib.get("main_tree_to_execute")
    trees = [bt.attrib.get("ID") for bt in root.findall("BehaviorTree")]
    if main_id is None:
        if len(trees) == 1:
            main_id = trees[0]
        else:
            found = ", ".join(str(t) for t in trees) or "none"
            problems.append(
                TreeProblem(
                    source,
                    root.sourceline,
                    describe(root),
                    f'cannot tell the main tree: expected main_tree_to_execute="..." on <root> '
                    f"naming one of the <BehaviorTree> IDs ({found})",
                )
            )
    elif main_id not in trees:
        found = ", ".join(str(t) for t in trees) or "none"
        problems.append(
            TreeProblem(
                source,
                root.sourceline,
                describe(root),
                f"main tree '{main_id}' not found; expected one of the <BehaviorTree> IDs: {found}",
            )
        )
    return TreeDocument(source, root, main_id, problems)


def _inline_includes(
    root: SourceElement, base_dir: str, visited: set[str], problems: list[TreeProblem]
) -> None:
    """Replace top-level ``<include path=...>`` (BT.CPP) / ``<Import src=...>`` with its trees."""
    for inc in [c for c in root if c.tag.lower() in ("include", "import")]:
        assert isinstance(inc, SourceElement)
        root.remove(inc)
        ref = inc.attrib.get("path") or inc.attrib.get("src") or inc.attrib.get("file")
        if not ref or "ros_pkg" in inc.attrib:
            problems.append(
                TreeProblem(
                    inc.sourcefile,
                    inc.sourceline,
                    describe(inc),
                    'expected a path="file.xml" attribute (relative to this file; ros_pkg '
                    "is not supported)",
                )
            )
            continue
        target = os.path.abspath(os.path.join(base_dir, ref))
        if target in visited:
            continue
        visited.add(target)
        try:
            data = Path(target).read_bytes()
        except OSError as exc:
            problems.append(
                TreeProblem(
                    inc.sourcefile,
                    inc.sourceline,
                    describe(inc),
                    f"cannot read included file '{ref}' ({target}): {exc.strerror}",
                )
            )
            continue
        try:
            shown = (
                ref if os.path.isabs(ref) else os.path.join(os.path.dirname(inc.sourcefile), ref)
            )
            other = _parse_xml(data, os.path.normpath(shown))
        except TreeFileError as exc:
            problems.extend(exc.problems)
            continue
        _inline_includes(other, os.path.dirname(target), visited, problems)
        for bt in other.findall("BehaviorTree"):
            root.append(bt)


def _drop_attribute(elem: ET.Element, old: str) -> str | None:
    return elem.attrib.pop(old, None)


def _translate(elem: ET.Element, registry: Registry, problems: list[TreeProblem]) -> None:
    """Rewrite one element from BT.CPP spelling to what py_trees' parser builds (in place)."""
    assert isinstance(elem, SourceElement)

    def problem(message: str) -> None:
        problems.append(TreeProblem(elem.sourcefile, elem.sourceline, describe(elem), message))

    if elem.tag in ("root", "BehaviorTree", "TreeNodesModel") or elem.tag in registry:
        return
    # Explicit form: <Action ID="Grasp" .../> is <Grasp .../>.
    if elem.tag in ("Action", "Condition", "Control", "Decorator") and "ID" in elem.attrib:
        elem.tag = elem.attrib.pop("ID")
        if elem.tag in registry:
            return
    for key in [k for k in elem.attrib if k.startswith("_")]:
        value = elem.attrib.pop(key)
        if key in _IGNORED_ATTRIBUTES or (key == "_autoremap" and value.lower() == "false"):
            continue
        problem(
            f"attribute '{key}' (BT.CPP scripting/pre-/post-conditions/_autoremap) is not "
            "supported by the py_trees parser; remap subtree ports explicitly"
        )
    lower = elem.tag.lower()
    # BT.CPP's SequenceWithMemory (no restart after a failure) has no py_trees equivalent.
    if lower in ("sequence", "reactivesequence"):
        elem.tag = "Sequence"
        if lower == "reactivesequence":
            elem.attrib.setdefault("memory", "false")
    elif lower in ("selector", "fallback", "reactivefallback"):
        elem.tag = "Selector"
        if lower == "reactivefallback":
            elem.attrib.setdefault("memory", "false")
    elif lower == "parallel":
        elem.tag = "Parallel"
        _translate_parallel(elem, problem)
    elif lower in ("retry", "retryuntilsuccessful"):
        elem.tag = "Retry"
        attempts = _drop_attribute(elem, "num_attempts")
        if attempts is not None:
            if attempts.strip() == "-1":
                problem('num_attempts="-1" (retry forever) is not supported; give a count >= 1')
            elem.attrib.setdefault("num_failures", attempts)
    elif lower == "timeout":
        elem.tag = "Timeout"
        msec = _drop_attribute(elem, "msec")
        if msec is not None:
            try:
                elem.attrib.setdefault("duration", repr(int(msec) / 1000.0))
            except ValueError:
                problem(
                    f"attribute 'msec': expected an integer number of milliseconds, got '{msec}'"
                )
    elif lower == "repeat":
        elem.tag = "Repeat"
        cycles = _drop_attribute(elem, "num_cycles")
        if cycles is not None:
            elem.attrib.setdefault("num_success", cycles)
    elif lower == "forcesuccess":
        elem.tag = "FailureIsSuccess"
    elif lower == "forcefailure":
        elem.tag = "SuccessIsFailure"
    elif lower in ("subtree", "subtreeplus"):
        elem.tag = "SubTree"
    elif lower in DECORATOR_NODES:
        elem.tag = DECORATOR_NODES[lower].__name__


def _translate_parallel(elem: ET.Element, problem: Callable[[str], None]) -> None:
    """Map BT.CPP ``success_count``/``failure_count`` to a py_trees policy (default: all)."""
    success = elem.attrib.pop("success_count", None)
    failure = elem.attrib.pop("failure_count", None)
    n_children = len(elem)
    if failure is not None and failure.strip() != "1":
        problem(
            f'failure_count="{failure}" is not supported: py_trees\' Parallel fails as soon as '
            'one child fails (failure_count="1")'
        )
    if success is None:
        # BT.CPP's default (and so an unannotated Groot tree's) is: succeed when all succeed.
        elem.attrib.setdefault("policy", "success_on_all")
        return
    try:
        count = int(success)
    except ValueError:
        problem(f"success_count: expected an integer, got '{success}'")
        return
    if count == -1 or count == n_children:
        elem.attrib.setdefault("policy", "success_on_all")
    elif count == 1:
        elem.attrib.setdefault("policy", "success_on_one")
    else:
        problem(
            f'success_count="{success}" is not supported; expected 1 (any child) or -1 / '
            f"{n_children} (all children)"
        )


# --------------------------------------------------------------------------------------------
# Checking
# --------------------------------------------------------------------------------------------


def effective_registry(registry: Registry | None = None) -> dict[str, Any]:
    """Return the tag -> class mapping the loader builds with.

    ``registry`` (default: py_trees' global ports registry, i.e. every imported concrete
    ports-enabled behaviour) plus ``Timeout`` -> :class:`~planner.decorators.SimTimeout`
    unless ``registry`` defines its own ``Timeout``.
    """
    reg = dict(get_ports_registry() if registry is None else registry)
    reg.setdefault("Timeout", SimTimeout)
    return reg


def registry_class(entry: Any) -> type | None:
    """Return the class behind a registry entry (a class or a ``functools.partial`` of one)."""
    if isinstance(entry, functools.partial):
        entry = entry.func
    return entry if inspect.isclass(entry) else None


@dataclass(frozen=True)
class _Param:
    annotation: Any
    required: bool


def constructor_params(entry: Any) -> dict[str, _Param]:
    """Named constructor parameters an XML attribute may set, most-derived class first.

    Parameters the parser fills itself (``name``, ``child``...) and ``*args``/``**kwargs`` are
    left out; those bound by a ``functools.partial`` registry entry are not required.
    """
    bound = set(entry.keywords) if isinstance(entry, functools.partial) else set()
    cls = registry_class(entry)
    params: dict[str, _Param] = {}
    if cls is None:
        return params
    for klass in cls.__mro__:
        if klass in (py_trees.behaviour.Behaviour, PortsMixin, object):
            continue
        if "__init__" not in vars(klass):
            continue
        try:
            signature = inspect.signature(vars(klass)["__init__"])
        except (TypeError, ValueError):
            continue
        for pname, param in signature.parameters.items():
            if pname in _IMPLICIT_PARAMS or pname in params:
                continue
            if param.kind in (param.VAR_POSITIONAL, param.VAR_KEYWORD):
                continue
            annotation = None if param.annotation is param.empty else param.annotation
            if isinstance(annotation, str):
                annotation = _resolve_annotation(klass, pname)
            required = param.default is param.empty and pname not in bound
            params[pname] = _Param(annotation, required)
    return params


def _resolve_annotation(klass: type, pname: str) -> Any:
    try:
        return typing.get_type_hints(vars(klass)["__init__"]).get(pname)
    except Exception:  # an unresolvable string annotation just means "no conversion check"
        return None


def type_name(tp: Any) -> str:
    """Short readable name of a port type: ``float``, ``list[float]``, ``numpy.ndarray``."""
    if get_origin(tp) is not None:
        return str(tp).replace("typing.", "")
    if inspect.isclass(tp):
        if tp.__module__ == "builtins":
            return tp.__name__
        return f"{tp.__module__}.{tp.__qualname__}"
    return str(tp)


def literal_problem(value: str, data_type: Any) -> str | None:
    """Return why ``value`` does not convert to ``data_type`` as the parser does, or None.

    Uses py_trees' own conversion (the one ``setup_ports`` applies), plus a length check for
    fixed-length tuples, which py_trees converts without checking.
    """
    if data_type is None or data_type is str or data_type is Any or data_type is object:
        return None
    expected = type_name(data_type)
    try:
        ok, converted = convert_str_to_type(value, data_type)
    except (ValueError, TypeError, KeyError):
        return f"cannot convert '{value}' to {expected}"
    if not ok:
        if not _literal_convertible(data_type):
            return (
                f"a {expected} cannot be written as a literal; pass it through a blackboard "
                "key such as {name}"
            )
        return f"cannot convert '{value}' to {expected}"
    if get_origin(data_type) is tuple:
        args = get_args(data_type)
        if args and Ellipsis not in args and len(converted) != len(args):
            return f"expected {len(args)} comma-separated values for {expected}, got '{value}'"
    return None


def _literal_convertible(tp: Any) -> bool:
    origin = get_origin(tp)
    if origin in (list, tuple):
        return all(_literal_convertible(a) for a in get_args(tp) if a is not Ellipsis)
    if origin is not None:
        return any(_literal_convertible(a) for a in get_args(tp) if a is not type(None))
    return tp in (str, int, float, bool) or (inspect.isclass(tp) and issubclass(tp, enum.Enum))


def _key_problem(value: str) -> tuple[bool, str | None]:
    """Return (is_key, problem) for an attribute value; ``{name}`` is a blackboard key."""
    opens, closes = value.count("{"), value.count("}")
    if opens == 0 and closes == 0:
        return False, None
    if (
        opens == 1
        and closes == 1
        and value.startswith("{")
        and value.endswith("}")
        and len(value) > 2
    ):
        return True, None
    return True, f"malformed blackboard key '{value}'; expected {{name}} or a literal"


def _one_of(names: list[str] | set[str]) -> str:
    return ", ".join(sorted(names)) if names else "none"


class _Checker:
    """Walks a translated document and collects problems."""

    def __init__(self, doc: TreeDocument, registry: Registry | None) -> None:
        self.doc = doc
        self.registry = effective_registry(registry)
        self.trees = doc.behaviour_trees()
        self.problems: list[TreeProblem] = []
        self._subtree_ports: dict[str, set[str]] = {}

    def add(self, elem: ET.Element, message: str) -> None:
        problem = TreeProblem(_file(elem, self.doc.file), _line(elem), describe(elem), message)
        if problem not in self.problems:
            self.problems.append(problem)

    def where(self, elem: ET.Element, seen_from: ET.Element) -> str:
        """``line N``, or ``file:N`` when ``elem`` is in another file than ``seen_from``."""
        file = _file(elem, self.doc.file)
        if file == _file(seen_from, self.doc.file):
            return f"line {_line(elem)}"
        return f"{file}:{_line(elem)}"

    # -- definitions --------------------------------------------------------------------
    def run(self) -> list[TreeProblem]:
        seen: dict[str, ET.Element] = {}
        for bt in self.doc.root.findall("BehaviorTree"):
            bt_id = bt.attrib.get("ID")
            if not bt_id:
                self.add(bt, 'expected an ID="..." attribute')
            elif bt_id in seen:
                self.add(
                    bt,
                    f"duplicate BehaviorTree ID '{bt_id}' (first at {self.where(seen[bt_id], bt)})",
                )
            else:
                seen[bt_id] = bt
            if len(bt) != 1:
                self.add(bt, f"expected exactly one child (the tree's root node), found {len(bt)}")
            for child in bt:
                self.check(child)
        for other in self.doc.root:
            if other.tag not in ("BehaviorTree", "TreeNodesModel"):
                self.add(other, "unexpected element under <root>; expected <BehaviorTree ID=...>")
        if self.doc.main_tree_id in self.trees:
            names: dict[str, ET.Element] = {}
            self.instantiate(
                self.trees[self.doc.main_tree_id], "", [self.doc.main_tree_id], names, None
            )
        return self.problems

    def check(self, elem: ET.Element) -> None:
        tag = elem.tag
        if tag in self.registry:
            self.check_ports_node(elem, self.registry[tag])
        elif tag in COMPOSITES:
            self.check_composite(elem)
        elif tag in _BUILTIN_DECORATORS:
            self.check_params(elem, _BUILTIN_DECORATORS[tag], allow_keys=True)
            self.check_children(elem, 1, 1, "decorator")
        elif tag == "SubTree":
            self.check_subtree(elem)
        else:
            self.unknown_tag(elem)
            return
        self.check_name(elem)
        for child in elem:
            self.check(child)

    def unknown_tag(self, elem: ET.Element) -> None:
        leaves = sorted(
            t for t, e in self.registry.items() if (c := registry_class(e)) and not _is_parent(c)
        )
        known = leaves + list(COMPOSITES) + ["Fallback", "SubTree"] + sorted(_BUILTIN_DECORATORS)
        guess = difflib.get_close_matches(elem.tag, known, n=1)
        hint = f"did you mean '{guess[0]}'? " if guess else ""
        self.add(
            elem,
            f"unknown node type '{elem.tag}'; {hint}expected a registered leaf "
            f"({_one_of(leaves)}), a control node (Sequence, Fallback/Selector, Parallel, "
            "a decorator) or <SubTree ID=...>",
        )

    def check_name(self, elem: ET.Element) -> None:
        name = elem.attrib.get("name")
        if name is not None and "." in name:
            self.add(elem, f"name '{name}': expected no '.' (py_trees joins parent names with '.')")

    def check_children(self, elem: ET.Element, low: int, high: int | None, what: str) -> None:
        n = len(elem)
        if high is not None and low == high and n != low:
            self.add(elem, f"a {what} takes exactly {low} child, found {n}")
        elif n < low:
            self.add(elem, f"a {what} needs at least {low} child, found {n}")
        elif high is not None and n > high:
            self.add(elem, f"a {what} takes at most {high} children, found {n}")

    def check_composite(self, elem: ET.Element) -> None:
        allowed = {"name", "memory"} if elem.tag != "Parallel" else {"name", "policy"}
        for key, value in elem.attrib.items():
            if key not in allowed:
                self.add(elem, f"unknown attribute '{key}'; expected one of {_one_of(allowed)}")
            elif key == "memory" and value.strip().lower() not in ("true", "false"):
                self.add(elem, f"attribute 'memory': expected true or false, got '{value}'")
            elif key == "policy" and value not in PARALLEL_POLICIES:
                self.add(
                    elem,
                    f"attribute 'policy': expected one of {', '.join(PARALLEL_POLICIES)}, "
                    f"got '{value}'",
                )
        self.check_children(elem, 1, None, "control node")

    def check_params(self, elem: ET.Element, entry: Any, allow_keys: bool) -> set[str]:
        """Check constructor-argument attributes; return the names accepted."""
        params = constructor_params(entry)
        for pname, param in params.items():
            if param.required and pname not in elem.attrib:
                self.add(elem, f"missing required attribute '{pname}'")
        for key, value in elem.attrib.items():
            if key not in params:
                continue
            is_key, bad = _key_problem(value)
            if bad:
                self.add(elem, f"attribute '{key}': {bad}")
            elif is_key and not allow_keys:
                self.add(
                    elem,
                    f"attribute '{key}' is a constructor argument; expected a literal, got the "
                    f"blackboard key '{value}'",
                )
            elif not is_key:
                bad = literal_problem(value, params[key].annotation)
                if bad:
                    self.add(elem, f"attribute '{key}': {bad}")
        unknown = [k for k in elem.attrib if k not in params and k != "name"]
        if registry_class(entry) in _BUILTIN_DECORATORS.values():
            for key in unknown:
                self.add(elem, f"unknown attribute '{key}'; expected one of {_one_of(set(params))}")
        return set(params)

    def check_ports_node(self, elem: ET.Element, entry: Any) -> None:
        cls = registry_class(entry)
        if cls is None or not issubclass(cls, PortsMixin):
            self.add(elem, f"registry entry for '{elem.tag}' is not a ports-enabled class")
            return
        inputs: dict[str, PortInformation] = cls.input_ports()
        outputs: dict[str, PortInformation] = cls.output_ports()
        params = self.check_params(elem, entry, allow_keys=False)
        accepted = set(inputs) | set(outputs) | params
        for key, value in elem.attrib.items():
            if key == "name" or key in params:
                continue
            if key not in inputs and key not in outputs:
                self.add(elem, f"unknown port '{key}'; expected one of {_one_of(accepted)}")
                continue
            is_key, bad = _key_problem(value)
            if bad:
                self.add(elem, f"port '{key}': {bad}")
            elif key in outputs and not is_key:
                self.add(
                    elem,
                    f"output port '{key}': expected a blackboard key such as {{{key}}}, got the "
                    f"literal '{value}'",
                )
            elif key in inputs and not is_key:
                bad = literal_problem(value, inputs[key].data_type)
                if bad:
                    self.add(elem, f"port '{key}': {bad}")
        for port, info in inputs.items():
            if info.required and not info.has_default and port not in elem.attrib:
                self.add(
                    elem,
                    f"missing required input port '{port}' ({type_name(info.data_type)}); "
                    f"give a literal or a blackboard key such as {{{port}}}",
                )
        if issubclass(cls, py_trees.decorators.Decorator):
            self.check_children(elem, 1, 1, "decorator")
        elif issubclass(cls, py_trees.composites.Composite):
            self.check_children(elem, 1, None, "control node")
        elif len(elem):
            self.add(elem, f"a leaf takes no children, found {len(elem)}")

    def subtree_ports(self, bt_id: str) -> set[str]:
        """Names a ``<SubTree>`` may remap: the tree's own attributes and the keys it uses."""
        if bt_id in self._subtree_ports:
            return self._subtree_ports[bt_id]
        bt = self.trees[bt_id]
        ports = {k for k in bt.attrib if k not in ("ID", "name")}
        self._subtree_ports[bt_id] = ports  # guards recursion through cycles
        for elem in bt.iter():
            if elem is bt:
                continue
            for value in elem.attrib.values():
                is_key, bad = _key_problem(value)
                if is_key and not bad:
                    ports.add(value[1:-1])
        return ports

    def check_subtree(self, elem: ET.Element) -> None:
        bt_id = elem.attrib.get("ID")
        if not bt_id:
            self.add(elem, 'expected an ID="..." attribute naming a <BehaviorTree>')
            return
        if bt_id not in self.trees:
            guess = difflib.get_close_matches(bt_id, list(self.trees), n=1)
            hint = f"did you mean '{guess[0]}'? " if guess else ""
            self.add(
                elem,
                f"unknown subtree '{bt_id}'; {hint}expected one of the <BehaviorTree> IDs: "
                f"{_one_of(set(self.trees))}",
            )
            return
        ports = self.subtree_ports(bt_id)
        for key, value in elem.attrib.items():
            if key in ("ID", "name"):
                continue
            if key not in ports:
                self.add(
                    elem,
                    f"unknown port '{key}' of subtree '{bt_id}'; expected one of {_one_of(ports)}",
                )
                continue
            is_key, bad = _key_problem(value)
            if bad:
                self.add(elem, f"port '{key}': {bad}")
            elif not is_key:
                self.check_subtree_literal(elem, bt_id, key, value)
        if len(elem):
            self.add(elem, f"a <SubTree> takes no children, found {len(elem)}")

    def check_subtree_literal(self, elem: ET.Element, bt_id: str, port: str, value: str) -> None:
        """Check a literal given to a subtree port against the leaf input ports using it."""
        for inner in self.trees[bt_id].iter():
            cls = registry_class(self.registry.get(inner.tag))
            if cls is None or not issubclass(cls, PortsMixin):
                continue
            for name, info in cls.input_ports().items():
                if inner.attrib.get(name) != f"{{{port}}}":
                    continue
                bad = literal_problem(value, info.data_type)
                if bad:
                    self.add(
                        elem,
                        f"port '{port}' feeds {describe(inner)} port '{name}' (line "
                        f"{_line(inner)}): {bad}",
                    )

    # -- instantiation: names as the parser makes them, subtree cycles ------------------
    def instantiate(
        self,
        elem: ET.Element,
        prefix: str,
        stack: list[str],
        names: dict[str, ET.Element],
        via: ET.Element | None,
    ) -> None:
        tag = elem.tag
        if tag == "BehaviorTree":
            for child in elem:
                self.instantiate(child, prefix, stack, names, via)
            return
        if tag == "SubTree":
            bt_id = elem.attrib.get("ID", "")
            if bt_id not in self.trees:
                return
            if bt_id in stack:
                cycle = " -> ".join([*stack[stack.index(bt_id) :], bt_id])
                self.add(elem, f"subtree cycle {cycle}; a tree cannot contain itself")
                return
            name = elem.attrib.get("name")
            if name is None:
                return  # the parser names it with a fresh uuid: nothing inside can clash
            inner = f"{prefix}.{name}" if prefix else name
            self.instantiate(self.trees[bt_id], inner, [*stack, bt_id], names, elem)
            return
        explicit = elem.attrib.get("name")
        if explicit:
            full = f"{prefix}.{explicit}" if prefix else explicit
            if full in names:
                first = names[full]
                culprit = via if via is not None else elem
                self.add(
                    culprit,
                    f"duplicate node name '{full}' (also at {self.where(first, culprit)}); "
                    "py_trees needs unique names: rename one or name its parent",
                )
            names.setdefault(full, elem)
            child_prefix = full
        else:
            child_prefix = prefix
        for child in elem:
            self.instantiate(child, child_prefix, stack, names, via)


def _is_parent(cls: type) -> bool:
    return issubclass(cls, (py_trees.decorators.Decorator, py_trees.composites.Composite))


def check_tree_document(doc: TreeDocument, registry: Registry | None = None) -> list[TreeProblem]:
    """Return every problem in a read document (reading problems first).

    Parameters
    ----------
    doc : TreeDocument
        From :func:`read_tree_document`.
    registry : mapping tag -> class, optional
        As for :func:`effective_registry`.
    """
    return [*doc.problems, *_Checker(doc, registry).run()]


def validate_tree(
    path: str | os.PathLike[str], registry: Registry | None = None
) -> list[TreeProblem]:
    """Check a tree file without building it; return its problems (empty when it is fine).

    Checks: XML syntax; unknown tags (not a registered leaf, control node or ``SubTree``);
    unknown, missing required and wrongly typed ports; output ports given literals; subtree
    IDs and their remapped ports; the main tree; child counts (decorators exactly one,
    control nodes at least one, leaves none); names the parser would duplicate; subtree cycles.
    """
    try:
        doc = read_tree_document(path, registry)
    except TreeFileError as exc:
        return list(exc.problems)
    return check_tree_document(doc, registry)


def validate_tree_string(
    text: str, source: str = "<string>", registry: Registry | None = None
) -> list[TreeProblem]:
    """Check tree XML given as a string (see :func:`validate_tree`)."""
    try:
        doc = read_tree_document_string(text, source, registry)
    except TreeFileError as exc:
        return list(exc.problems)
    return check_tree_document(doc, registry)


def tree_cli_validate(path: str | os.PathLike[str], registry: Registry | None = None) -> int:
    """Validate a tree file for the command line.

    Prints each problem on its own line to stderr and returns 2, or prints a one-line
    ``ok`` summary to stdout and returns 0.
    """
    problems = validate_tree(path, registry)
    if problems:
        for problem in problems:
            print(problem, file=sys.stderr)
        plural = "s" if len(problems) != 1 else ""
        print(f"{os.fspath(path)}: {len(problems)} problem{plural}", file=sys.stderr)
        return 2
    doc = read_tree_document(path, registry)
    n_nodes = sum(1 for bt in doc.root.findall("BehaviorTree") for _ in _nodes(bt))
    n_trees = len(doc.behaviour_trees())
    print(
        f"{os.fspath(path)}: ok (main tree '{doc.main_tree_id}', {n_trees} tree"
        f"{'s' if n_trees != 1 else ''}, {n_nodes} nodes)"
    )
    return 0


def _nodes(bt: ET.Element) -> Iterator[ET.Element]:
    for elem in bt.iter():
        if elem is not bt:
            yield elem
