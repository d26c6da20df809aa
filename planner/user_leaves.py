"""A user's own leaves: registered from a file, a module or an installed package's entry point.

A leaf is a :class:`planner.leaves.WorldLeaf` subclass with ``INPUT_PORTS``, ``OUTPUT_PORTS``
and ``update()`` (the README's leaf API). Defining one registers it in py_trees' ports
registry under its class name, which is what the XML loader builds from; this module brings
the definitions in:

- ``--leaves my_leaves.py`` (a file) or ``--leaves my_package.leaves`` (an importable module):
  every ``WorldLeaf`` subclass *defined in* that module is registered by its class name;
- every entry point of the group ``duet.leaves`` of the installed distributions, e.g. in a
  package's ``pyproject.toml``::

      [project.entry-points."duet.leaves"]
      my_leaves = "my_package.leaves"

  names a module (all its ``WorldLeaf`` subclasses) or one ``WorldLeaf`` subclass.

A module may also declare the enum names its trees' scripts use, ``SCRIPT_ENUMS`` (see
:mod:`planner.script_enums`; a module of only enums is fine).

Problems raise :class:`LeafSourceError`, naming the file, module or entry point and what was
expected. The registration is global to the process: a worker process of a campaign calls
:func:`register_leaves` again with the same sources (a forked one inherits it anyway).
"""

from __future__ import annotations

import contextlib
import hashlib
import importlib
import importlib.util
import inspect
import re
import sys
import traceback
import warnings
from collections.abc import Iterable, Iterator, Sequence
from importlib.metadata import EntryPoint, entry_points
from pathlib import Path
from types import ModuleType

from py_trees.ports import PortInformation, get_ports_registry, register_ports_class

from planner.leaves import WorldLeaf
from planner.nodes_model import NODE_KINDS
from planner.script_enums import ScriptEnumError, register_script_enums
from planner.tree_ports import builtin_nodes
from planner.tree_reading import TRANSLATED_TAGS

#: The entry-point group an installed package ships leaves in.
ENTRY_POINT_GROUP = "duet.leaves"

_MODULE_PATH = re.compile(r"[A-Za-z_][A-Za-z0-9_]*(\.[A-Za-z_][A-Za-z0-9_]*)*")
_EXPECTED = "a Python file or module defining planner.leaves.WorldLeaf subclasses"


class LeafSourceError(ValueError):
    """A leaf source (file, module, entry point) that cannot be registered; says why."""


def register_leaves(
    sources: Sequence[str] = (), *, entry_point_group: str | None = ENTRY_POINT_GROUP
) -> list[type[WorldLeaf]]:
    """Register the leaves of ``sources`` and of the installed ``duet.leaves`` entry points.

    Parameters
    ----------
    sources : sequence of str
        Each a ``.py`` file (a path) or a dotted module path.
    entry_point_group : str or None
        The entry-point group to load as well; None for none.

    Returns
    -------
    list of type
        The leaf classes registered, sources first, in definition order.

    Raises
    ------
    LeafSourceError
        A file missing, a module that does not import (with its error), a source defining
        no leaf, a leaf without ports, or a leaf whose name a shipped leaf already has.
    """
    registered: list[type[WorldLeaf]] = []
    for source in sources:
        before = get_ports_registry()
        with warnings.catch_warnings():  # a clash is refused below, with its reason
            warnings.simplefilter("ignore")
            module = _import_source(source)
        label = f"--leaves {source}"
        enums = _register_enums(module, label)
        registered += _register(_leaves_defined_in(module), label, before, enums)
    if entry_point_group is not None:
        for ep in entry_points(group=entry_point_group):
            before = get_ports_registry()
            label = _entry_point_label(ep)
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                target = _load_entry_point(ep)
            enums = _register_enums(target, label) if isinstance(target, ModuleType) else False
            registered += _register(_leaves_of_entry_point(ep, target), label, before, enums)
    return registered


def _register_enums(module: ModuleType, label: str) -> bool:
    """Register the module's ``SCRIPT_ENUMS`` (:mod:`planner.script_enums`); whether it has."""
    if not hasattr(module, "SCRIPT_ENUMS"):
        return False
    try:
        register_script_enums(module.SCRIPT_ENUMS, label)
    except ScriptEnumError as err:
        raise LeafSourceError(str(err)) from None
    return True


def _import_source(source: str) -> ModuleType:
    path = Path(source)
    if source.endswith(".py") or path.is_file() or "/" in source or "\\" in source:
        return _import_file(source, path)
    if _MODULE_PATH.fullmatch(source) is None:
        raise LeafSourceError(
            f"--leaves {source}: expected {_EXPECTED} (a path ending in .py or a dotted "
            "module path), got neither"
        )
    try:
        return importlib.import_module(source)
    except ModuleNotFoundError as err:
        if err.name is not None and source.startswith(err.name):
            raise LeafSourceError(
                f"--leaves {source}: expected {_EXPECTED}, got no module named {err.name!r} "
                "(a file needs its .py)"
            ) from None
        raise LeafSourceError(f"--leaves {source}: cannot import it: {_describe(err)}") from None
    except (Exception, SystemExit) as err:  # a user's module may raise anything, exit too
        raise LeafSourceError(f"--leaves {source}: cannot import it: {_describe(err)}") from None


def _import_file(source: str, path: Path) -> ModuleType:
    if not path.is_file():
        what = "a folder" if path.is_dir() else "no such file"
        raise LeafSourceError(f"--leaves {source}: expected {_EXPECTED}, got {what}")
    resolved = path.resolve()
    # One module per file, named after its path: importing it again (another command, a
    # worker) finds the same module and the same classes.
    digest = hashlib.sha1(str(resolved).encode()).hexdigest()[:10]
    stem = re.sub(r"\W", "_", resolved.stem)
    name = f"duet_user_leaves.{stem}_{digest}"
    if name in sys.modules:
        return sys.modules[name]
    spec = importlib.util.spec_from_file_location(name, resolved)
    if spec is None or spec.loader is None:
        raise LeafSourceError(
            f"--leaves {source}: expected {_EXPECTED}, got a file Python cannot load"
        )
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    try:
        with _own_folder_first(resolved.parent):
            spec.loader.exec_module(module)
    except (Exception, SystemExit) as err:  # a user's file may raise anything, exit too
        del sys.modules[name]
        raise LeafSourceError(
            f"--leaves {source}: cannot import it: {_describe(err, resolved)}"
        ) from None
    return module


#: The helper modules each leaf file's folder gave, by folder: module names to modules.
_FOLDER_MODULES: dict[Path, dict[str, ModuleType]] = {}


@contextlib.contextmanager
def _own_folder_first(folder: Path) -> Iterator[None]:
    """While a leaf file is imported, its folder is searched first for the modules it
    imports (``from helpers import speed`` beside it), as ``python file.py`` searches it, and
    a module of that name another leaf folder gave is set aside (two folders' ``helpers.py``
    each the one its own file imports); afterwards the search path is as it was."""
    before = set(sys.modules)
    for other, modules in _FOLDER_MODULES.items():
        for module_name, module in modules.items():
            if other != folder and sys.modules.get(module_name) is module:
                del sys.modules[module_name]
    sys.path.insert(0, str(folder))
    try:
        yield
    finally:
        sys.path.remove(str(folder))
        own = _FOLDER_MODULES.setdefault(folder, {})
        for module_name in set(sys.modules) - before:
            module = sys.modules[module_name]
            file = getattr(module, "__file__", None)
            if file is not None and Path(file).resolve().is_relative_to(folder):
                own[module_name] = module


def _describe(err: BaseException, file: Path | None = None) -> str:
    """``SyntaxError: invalid syntax (line 3)``: the error and where in the user's file."""
    line = getattr(err, "lineno", None) if isinstance(err, SyntaxError) else None
    if line is None and file is not None:
        frames = [f for f in traceback.extract_tb(err.__traceback__) if Path(f.filename) == file]
        line = frames[-1].lineno if frames else None
    message = getattr(err, "msg", None) if isinstance(err, SyntaxError) else str(err)
    where = f" (line {line})" if line is not None else ""
    if isinstance(err, SystemExit):  # script code outside an `if __name__ == "__main__":`
        return f"it called sys.exit({err.code!r}){where}"
    return f"{type(err).__name__}: {message}{where}"


def _leaves_defined_in(module: ModuleType) -> list[type[WorldLeaf]]:
    return [
        cls
        for _, cls in inspect.getmembers(module, inspect.isclass)
        if issubclass(cls, WorldLeaf) and cls.__module__ == module.__name__
    ]


def _load_entry_point(ep: EntryPoint) -> object:
    try:
        return ep.load()
    except (Exception, SystemExit) as err:  # a package may raise anything, exit too
        raise LeafSourceError(
            f"{_entry_point_label(ep)}: cannot load it: {_describe(err)}"
        ) from None


def _leaves_of_entry_point(ep: EntryPoint, target: object) -> list[type[WorldLeaf]]:
    label = _entry_point_label(ep)
    if isinstance(target, ModuleType):
        return _leaves_defined_in(target)
    if inspect.isclass(target) and issubclass(target, WorldLeaf):
        return [target]
    raise LeafSourceError(
        f"{label}: expected a module or a planner.leaves.WorldLeaf subclass, got {target!r}"
    )


def _entry_point_label(ep: EntryPoint) -> str:
    dist = getattr(ep, "dist", None)
    package = f" of {dist.name}" if dist is not None else ""
    return f"entry point {ep.name} = {ep.value!r}{package} ({ENTRY_POINT_GROUP})"


def _register(
    leaves: Iterable[type[WorldLeaf]],
    label: str,
    before: dict[str, type],
    has_enums: bool = False,
) -> list[type[WorldLeaf]]:
    """Register the concrete leaves (those with ports) under their class names.

    ``before`` is the registry as it was before the source was imported (defining a leaf
    registers it at once): a name that was another class's is restored and refused. A source
    with ``SCRIPT_ENUMS`` (``has_enums``) may define no leaf.
    """
    found = list(leaves)
    concrete = [c for c in found if _has_ports(c)]
    if not concrete and has_enums and not found:
        return []
    if not concrete:
        abstract = f" ({', '.join(c.__name__ for c in found)} declare no ports)" if found else ""
        raise LeafSourceError(
            f"{label}: expected at least one planner.leaves.WorldLeaf subclass with "
            f"INPUT_PORTS or OUTPUT_PORTS defined in it, got none{abstract}"
        )
    for cls in concrete:
        name = cls.__name__
        if name.lower() in TRANSLATED_TAGS or name in builtin_nodes():
            _restore_registry(before)  # defining it registered it, over the loader's meaning
            raise LeafSourceError(
                f"{label}: leaf {name}: expected a name no built-in node has, got that of "
                f"BehaviorTree.CPP's {name} (a tree's <{name}> would build the leaf)"
            )
        wrong = _declaration_problem(cls)
        if wrong:
            _restore_registry(before)
            raise LeafSourceError(f"{label}: leaf {name}: {wrong}")
        other = before.get(name)
        if other is not None and other is not cls:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                register_ports_class(name, other)
            raise LeafSourceError(
                f"{label}: leaf {name}: expected a name no registered leaf has, got that of "
                f"{other.__module__}.{other.__qualname__}"
            )
        if get_ports_registry().get(name) is not cls:
            register_ports_class(name, cls)
    return concrete


def _declaration_problem(cls: type) -> str:
    """What is wrong with a leaf's class-level declarations, or "": every port a
    ``PortInformation`` under a string name, and ``NODE_TYPE`` one the tree formats know."""
    for table in ("INPUT_PORTS", "OUTPUT_PORTS"):
        for port, info in getattr(cls, table).items():
            if not isinstance(port, str) or not isinstance(info, PortInformation):
                return (
                    f"{table}[{port!r}]: expected a py_trees.ports.PortInformation under a "
                    f"port name, got {type(info).__name__} {info!r:.60}"
                )
            wrong = port_name_problem(port)
            if wrong:
                return f"{table}[{port!r}]: {wrong}"
    kind = getattr(cls, "NODE_TYPE", "Action")
    if kind not in NODE_KINDS:
        return f"NODE_TYPE: expected one of {', '.join(NODE_KINDS)}, got {kind!r:.60}"
    return ""


#: What BehaviorTree.CPP v4 forbids in a port's name (``findForbiddenChar``).
_FORBIDDEN_IN_PORT_NAMES = frozenset(" \t\n\r<>&\"'/\\:*?|.")
#: Attributes a node's XML element keeps for itself (``IsReservedAttribute``): its ``name``,
#: ``ID`` and ``_autoremap`` (the scripting attributes start with ``_`` too).
_RESERVED_PORT_NAMES = frozenset({"name", "ID", "_autoremap"})


def port_name_problem(port: str) -> str:
    """What BehaviorTree.CPP v4 refuses in a port's name (``IsAllowedPortName``), or "": it
    starts with an ASCII letter (``_`` is kept for the scripting attributes), holds no
    character that breaks XML or paths, and is not an attribute the element keeps for itself
    (a port ``name`` would read the node's name; one starting with ``_`` could never be
    set)."""
    first = port[:1]
    if not (first.isascii() and first.isalpha()):
        return "expected a port name starting with a letter (BehaviorTree.CPP reserves '_')"
    bad = sorted({c for c in port if c in _FORBIDDEN_IN_PORT_NAMES})
    if bad:
        return f"expected a port name without {' '.join(repr(c) for c in bad)}"
    if port in _RESERVED_PORT_NAMES:
        return (
            f"expected a port name other than {', '.join(sorted(_RESERVED_PORT_NAMES))}, "
            "which a node's element keeps for itself"
        )
    return ""


def _restore_registry(before: dict[str, type]) -> None:
    """py_trees' ports registry as it was (``before``): py_trees has no call that removes a
    tag, so its module's table is set back."""
    import py_trees.ports

    table: dict[str, type] = py_trees.ports._REGISTRY
    table.clear()
    table.update(before)


def _has_ports(cls: type) -> bool:
    """A concrete leaf declares its ports: INPUT_PORTS, OUTPUT_PORTS or both (BT.CPP's
    ``providedPorts()`` may list inputs only). The one it leaves out is set to ``{}``."""
    inputs = isinstance(getattr(cls, "INPUT_PORTS", None), dict)
    outputs = isinstance(getattr(cls, "OUTPUT_PORTS", None), dict)
    if inputs != outputs:
        setattr(cls, "OUTPUT_PORTS" if inputs else "INPUT_PORTS", {})
    return inputs or outputs
