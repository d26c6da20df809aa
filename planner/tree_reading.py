"""Reading a tree file: expat with the line of every element, ``<include>`` inlined, and BT.CPP
spellings (``Fallback``, ``RetryUntilSuccessful num_attempts=``, ``Timeout msec=`` ...)
translated into the tags py_trees' parser builds."""

from __future__ import annotations

import os
import re
import xml.etree.ElementTree as ET
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from xml.parsers import expat

from py_trees.parsers.behaviour_tree_xml import DECORATOR_NODES
from py_trees.ports import get_ports_registry

from planner.bt_controls import parallel_threshold
from planner.bt_script import Script
from planner.bt_updated import BUILTIN_UPDATED
from planner.tree_ports import Registry, builtin_nodes
from planner.tree_problems import TreeFileError, TreeProblem
from planner.tree_syntax import (
    CONDITION_ATTRIBUTES,
    parse_attribute_script,
    rewrite_port_syntax,
    translate_script_node,
    underscore_problem,
)

#: Groot/BT.CPP bookkeeping attributes that carry no meaning for a run; dropped silently.
_IGNORED_ATTRIBUTES = frozenset({"_description", "_uid", "_fullpath"})


class SourceElement(ET.Element):
    """An element that remembers where it was written.

    ``sourcefile`` and ``sourceline`` locate the start tag; ``source_tag`` and ``source_attrib``
    keep the spelling as written, before BT.CPP names are translated, for messages.
    """

    sourcefile: str
    sourceline: int
    source_tag: str
    source_attrib: dict[str, str]
    #: BT.CPP pre/post-condition attributes, parsed (the py_trees parser never sees them).
    conditions: dict[str, Script]
    #: ``_autoremap="true"`` (a ``<SubTree>``).
    autoremap: bool


def describe(elem: ET.Element) -> str:
    """Return the element as written for messages, e.g. ``<Grasp name="grip">``."""
    tag = getattr(elem, "source_tag", elem.tag)
    attrib = getattr(elem, "source_attrib", elem.attrib)
    parts = [tag]
    for key in ("ID", "name"):
        if key in attrib:
            parts.append(f'{key}="{attrib[key]}"')
    return "<" + " ".join(parts) + ">"


def source_line(elem: ET.Element) -> int | None:
    """1-based line of an element's start tag, if it was read from text."""
    return getattr(elem, "sourceline", None)


def source_file(elem: ET.Element, default: str) -> str:
    """The file an element was read from (an include's), else ``default``."""
    return getattr(elem, "sourcefile", default)


_ENTITY = re.compile(r"&(?:#[0-9]+|#x[0-9a-fA-F]+|[A-Za-z_][\w.-]*);")


def lenient_xml(text: str) -> str:
    """The text as BT.CPP's XML parser (tinyxml2) reads it, made well-formed for expat: a bare
    ``<`` or ``&`` in an attribute value (``_skipIf="A<2"``, ``if="a && b"``, as BT.CPP's
    own examples write them) escaped, and an XML declaration after leading white space
    blanked. Lines and everything else are kept."""
    out: list[str] = []
    i, n = 0, len(text)
    start = len(text) - len(text.lstrip())
    if start and text.startswith("<?xml", start):
        end = text.find("?>", start)
        if end >= 0:
            text = text[:start] + " " * (end + 2 - start) + text[end + 2 :]
    while i < n:
        if (
            text.startswith("<!--", i)
            or text.startswith("<![CDATA[", i)
            or text.startswith("<?", i)
        ):
            close = {"<!--": "-->", "<![CDATA[": "]]>", "<?": "?>"}
            opener = next(o for o in close if text.startswith(o, i))
            end = text.find(close[opener], i)
            end = n if end < 0 else end + len(close[opener])
            out.append(text[i:end])
            i = end
            continue
        if text[i] != "<":
            out.append(text[i])
            i += 1
            continue
        # A tag: copy it, escaping inside its quoted values, up to the '>' outside quotes.
        quote = ""
        while i < n:
            c = text[i]
            if quote:
                if c == quote:
                    quote = ""
                elif c == "<":
                    c = "&lt;"
                elif c == "&" and not _ENTITY.match(text, i):
                    c = "&amp;"
            elif c in "\"'":
                quote = c
            out.append(c)
            i += 1
            if not quote and c == ">":
                break
    return "".join(out)


def _parse_xml(data: bytes | str, source: str) -> SourceElement:
    """Parse XML text into :class:`SourceElement` s; raise TreeFileError on a syntax error.

    Text expat refuses is read again through :func:`lenient_xml` (as BT.CPP would read it);
    the error reported is the first one.
    """
    try:
        return _parse_strict(data, source)
    except TreeFileError:
        try:
            text = data.decode("utf-8") if isinstance(data, bytes) else data
            return _parse_strict(lenient_xml(text), source)
        except (UnicodeDecodeError, TreeFileError):
            pass
        raise


def _parse_strict(data: bytes | str, source: str) -> SourceElement:
    parser = expat.ParserCreate()
    stack: list[SourceElement] = []
    document: list[SourceElement] = []

    def start(tag: str, attrib: dict[str, str]) -> None:
        elem = SourceElement(tag, attrib)
        elem.sourcefile = source
        elem.sourceline = parser.CurrentLineNumber
        elem.source_tag = tag
        elem.source_attrib = dict(attrib)
        elem.conditions = {}
        elem.autoremap = False
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
        data = read_tree_bytes(Path(source))
    except OSError as exc:
        raise TreeFileError(
            [
                TreeProblem(
                    source,
                    None,
                    "",
                    _unreadable(exc),
                )
            ]
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
    unnamed = [bt for bt in root.findall("BehaviorTree") if "ID" not in bt.attrib]
    if len(root.findall("BehaviorTree")) == 1 and unnamed:
        # BT.CPP: a file's only <BehaviorTree> may go without an ID; it is the main tree.
        unnamed[0].attrib["ID"] = UNNAMED_TREE_ID
    visited = {os.path.abspath(source)} if os.path.exists(source) else set()
    _inline_includes(root, base_dir, visited, problems)
    # Translate against the caller's registry only: a user-registered tag wins over a BT.CPP
    # spelling, but our own default Timeout still takes the BT.CPP ``msec`` spelling.
    user = {**builtin_nodes(), **(get_ports_registry() if registry is None else registry)}
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
                    f"(or --main-tree ID; a file saved by Groot2 has none) naming one of the "
                    f"<BehaviorTree> IDs ({found})",
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
    rewrite_port_syntax(root, main_id)
    return TreeDocument(source, root, main_id, problems)


#: The ID given to a file's only ``<BehaviorTree>`` when it has none (as BT.CPP does).
UNNAMED_TREE_ID = "MainTree"
#: Longest Timeout a tree may ask for, ms: a day of simulated time.
MAX_TIMEOUT_MS = 86_400_000
#: Largest tree file read, bytes (the shipped trees are 5-10 KB).
MAX_TREE_BYTES = 1 << 20


def _unreadable(exc: OSError) -> str:
    """What a tree file that cannot be read is, against what was expected."""
    why = str(exc.strerror or exc)
    if why.startswith("expected"):  # read_tree_bytes says it so already
        return why
    return f"expected a readable BehaviorTree.CPP XML file, got {why[:1].lower()}{why[1:]}"


def read_tree_bytes(path: Path) -> bytes:
    """The bytes of a tree file: a regular file (never a device, a pipe or a folder, which
    could block or never end) of at most :data:`MAX_TREE_BYTES`.

    Raises
    ------
    OSError
        Saying why, if it is not such a file or cannot be read.
    """
    if path.exists() and not path.is_file():
        raise OSError(
            f"expected a regular file, got {'a folder' if path.is_dir() else 'a device or pipe'}"
        )
    with open(path, "rb") as fh:
        data = fh.read(MAX_TREE_BYTES + 1)
    if len(data) > MAX_TREE_BYTES:
        raise OSError(f"expected a tree file of at most {MAX_TREE_BYTES} bytes, got more")
    return data


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
            data = read_tree_bytes(Path(target))
        except OSError as exc:
            problems.append(
                TreeProblem(
                    inc.sourcefile,
                    inc.sourceline,
                    describe(inc),
                    f"cannot read included file '{ref}' ({target}): {exc.strerror or exc}",
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


#: ``" {key} "``: a blackboard key with white space around it.
_SPACED_KEY = re.compile(r"\s*\{[^{}]+\}\s*")
#: BT.CPP's spellings of a boolean attribute (``convertFromString<bool>``).
_TRUE = frozenset({"true", "True", "TRUE", "1"})
_FALSE = frozenset({"false", "False", "FALSE", "0"})
#: Built-in nodes whose port names a key, which BT.CPP lets a tree write bare (``key="x"``).
_BARE_KEY_PORTS = {
    "SetBlackboard": "output_key",
    "UnsetBlackboard": "key",
    **dict.fromkeys(BUILTIN_UPDATED, "entry"),
}


def _drop_attribute(elem: ET.Element, old: str) -> str | None:
    return elem.attrib.pop(old, None)


def _translate(elem: ET.Element, registry: Registry, problems: list[TreeProblem]) -> None:
    """Rewrite one element from BT.CPP spelling to what py_trees' parser builds (in place)."""
    assert isinstance(elem, SourceElement)

    def problem(message: str) -> None:
        problems.append(TreeProblem(elem.sourcefile, elem.sourceline, describe(elem), message))

    if elem.tag in ("root", "BehaviorTree", "TreeNodesModel"):
        return
    for key, value in elem.attrib.items():
        if value != value.strip() and _SPACED_KEY.fullmatch(value):
            elem.attrib[key] = value.strip()  # BT.CPP trims a key's white space
    for key in [k for k in elem.attrib if k.startswith("_")]:
        value = elem.attrib.pop(key)
        if key in _IGNORED_ATTRIBUTES or (key == "_autoremap" and value.strip() in _FALSE):
            continue
        if key == "_autoremap" and value.strip() in _TRUE:
            elem.autoremap = True  # expanded by planner.tree_syntax
            continue
        if key in CONDITION_ATTRIBUTES:
            script = parse_attribute_script(value, key, problem)
            if script is not None:
                elem.conditions[key] = script
            continue
        problem(underscore_problem(key))
    translate_script_node(elem, problem)
    explicit = elem.tag in ("Action", "Condition", "Control", "Decorator")
    port = _BARE_KEY_PORTS.get(elem.attrib.get("ID", "") if explicit else elem.tag)
    if port is not None:
        named = elem.attrib.get(port)
        if named is not None and not named.startswith("{"):
            elem.attrib[port] = "{" + named + "}"  # BT.CPP names the key bare
    if elem.tag in registry:
        return
    # Explicit form: <Action ID="Grasp" .../> is <Grasp .../>.
    if elem.tag in ("Action", "Condition", "Control", "Decorator") and "ID" in elem.attrib:
        elem.tag = elem.attrib.pop("ID")
        if elem.tag in registry:
            return
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
        attempts = elem.attrib.get("num_attempts")
        if attempts is not None and (_not_positive(attempts) or attempts.startswith("{")):
            elem.tag = "RetryForever"  # BT.CPP semantics, the count read every tick
            return
        attempts = _drop_attribute(elem, "num_attempts")
        if attempts is not None:
            elem.attrib.setdefault("num_failures", attempts)
    elif lower == "timeout":
        elem.tag = "Timeout"
        if elem.attrib.get("msec", "").startswith("{"):
            elem.tag = "TimeoutFromKey"  # read from the blackboard when entered
            return
        msec = _drop_attribute(elem, "msec")
        if msec is None and "duration" not in elem.attrib:
            problem("missing required attribute 'msec': the time allowed, ms (BT.CPP's Timeout)")
        if msec is not None:
            ms: int | None
            try:
                ms = int(msec) if len(msec.strip()) <= 12 else None
            except ValueError:
                ms = None
            if ms is None or not 0 < ms <= MAX_TIMEOUT_MS:
                problem(
                    "attribute 'msec': expected a whole number of milliseconds from 1 to "
                    f"{MAX_TIMEOUT_MS}, got {msec[:40]!r}"
                )
            else:
                elem.attrib.setdefault("duration", repr(ms / 1000.0))
    elif lower == "repeat":
        elem.tag = "Repeat"
        count = elem.attrib.get("num_cycles", "")
        if count.startswith("{") or _not_positive(count):
            elem.tag = "RepeatFromKey"
            return
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


#: The tags, lower-cased, that the file format or :func:`translate` gives a meaning of their
#: own (controls, decorators and the document's structure): no leaf can be named so.
TRANSLATED_TAGS = frozenset(
    {
        "root",
        "behaviortree",
        "treenodesmodel",
        "include",
        "action",
        "condition",
        "control",
        "decorator",
        "sequence",
        "reactivesequence",
        "selector",
        "fallback",
        "reactivefallback",
        "parallel",
        "retry",
        "retryuntilsuccessful",
        "timeout",
        "repeat",
        "forcesuccess",
        "forcefailure",
        "subtree",
        "subtreeplus",
        *DECORATOR_NODES,
    }
)


def _not_positive(count: str) -> bool:
    """Whether a loop's literal count is 0 or negative: -1 loops for ever, and BT.CPP's
    ``Repeat`` and ``RetryUntilSuccessful`` run no cycle at all for 0 and any other negative
    count (``RetryForever``, ``RepeatFromKey`` read them so)."""
    try:
        return int(count.strip()) <= 0
    except ValueError:
        return False


def _translate_parallel(elem: ET.Element, problem: Callable[[str], None]) -> None:
    """Map BT.CPP ``success_count``/``failure_count`` to a py_trees policy (default: all)."""
    success = elem.attrib.get("success_count")
    failure = elem.attrib.get("failure_count")
    n_children = len(elem)
    simple = success is None or success.strip() in ("-1", "1", str(n_children))
    if (failure is not None and failure.strip() != "1") or not simple:
        elem.tag = "ParallelCount"  # BT.CPP's thresholds, see planner.bt_controls
        for name, value in (("success_count", success), ("failure_count", failure)):
            if value is None or value.startswith("{"):
                continue
            try:
                count = int(value)
            except ValueError:
                continue  # the port's type check names it
            if parallel_threshold(count, n_children) > n_children:
                problem(
                    f"attribute '{name}': expected at most {n_children} (the number of "
                    f"children; a negative count is that many fewer than all but one: -1 "
                    f"all), got {count}"
                )
        return
    elem.attrib.pop("success_count", None)
    elem.attrib.pop("failure_count", None)
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
