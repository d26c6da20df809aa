"""Reading the project's YAML files (world files, rule files) so that no document can hang it.

Three things a hostile or careless file can do to a plain ``yaml.safe_load``:

* repeat a key (PyYAML keeps the last one silently): refused, naming the key;
* be an alias bomb: nine levels of nine aliases is a tiny file whose expansion has 9^9
  nodes; PyYAML shares the aliased objects, but anything that walks them (a validator, an
  error message) expands them. The composed document's expanded size is counted from its
  node graph (each node once) and refused above :data:`MAX_EXPANDED_NODES`;
* be huge: files over :data:`MAX_FILE_BYTES` are refused before they are parsed.

:func:`shown` is the bounded repr every error message uses for a received value: cut by
depth, by items and by length, whatever the value holds.
"""

from __future__ import annotations

import re
import reprlib
from pathlib import Path
from typing import Any

import yaml

#: Largest YAML file read, bytes (the shipped world files are 4-8 KB).
MAX_FILE_BYTES = 1 << 20
#: Largest document, counted with every alias expanded.
MAX_EXPANDED_NODES = 100_000


class YamlFileError(ValueError):
    """A YAML file that cannot be read safely: ``problem`` says why, with line and column
    where they are known."""

    def __init__(self, problem: str, line: int | None = None, column: int | None = None):
        super().__init__(problem)
        self.problem = problem
        self.line = line
        self.column = column


class _StrictLoader(yaml.SafeLoader):
    """Safe YAML loader that rejects duplicate keys (PyYAML silently keeps the last one)."""


def _construct_mapping(loader: yaml.SafeLoader, node: yaml.MappingNode) -> dict[Any, Any]:
    # Only keys written in this mapping count: keys merged in with "<<" may be overridden.
    seen: set[Any] = set()
    for key_node, _ in node.value:
        if key_node.tag == "tag:yaml.org,2002:merge":
            continue
        key = loader.construct_object(key_node, deep=True)
        try:
            duplicate = key in seen
            seen.add(key)
        except TypeError:
            raise yaml.constructor.ConstructorError(
                "while constructing a mapping",
                node.start_mark,
                "found an unhashable key",
                key_node.start_mark,
            ) from None
        if duplicate:
            raise yaml.constructor.ConstructorError(
                "while constructing a mapping",
                node.start_mark,
                f"found duplicate key {shown(key)}",
                key_node.start_mark,
            )
    return loader.construct_mapping(node, deep=True)


_StrictLoader.add_constructor(yaml.resolver.BaseResolver.DEFAULT_MAPPING_TAG, _construct_mapping)

# PyYAML reads YAML 1.1, where a float needs a dot and a signed exponent: ``4e-2`` and
# ``1.5e3`` were text, and a world's ``radius: 4e-2`` was refused as "expected a number, got
# '4e-2'". YAML 1.2, which editors and the JSON Schema of `app.py schema` follow, reads them
# as numbers; so does this loader (integers and 1.1's floats resolve first, as before).
_StrictLoader.add_implicit_resolver(
    "tag:yaml.org,2002:float",
    re.compile(r"^[-+]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)[eE][-+]?[0-9]+$"),
    list("-+.0123456789"),
)


def expanded_size(root: yaml.Node) -> int:
    """How many nodes the document has with every alias expanded (each node visited once)."""
    sizes: dict[int, int] = {}
    order: list[yaml.Node] = []
    stack = [root]
    while stack:  # children before parents, without recursion
        node = stack.pop()
        if id(node) in sizes:
            continue
        sizes[id(node)] = -1
        order.append(node)
        if isinstance(node, yaml.SequenceNode):
            stack.extend(node.value)
        elif isinstance(node, yaml.MappingNode):
            for key, value in node.value:
                stack.extend((key, value))
    for node in reversed(order):
        total = 1
        if isinstance(node, yaml.SequenceNode):
            total += sum(sizes[id(child)] for child in node.value)
        elif isinstance(node, yaml.MappingNode):
            total += sum(sizes[id(k)] + sizes[id(v)] for k, v in node.value)
        sizes[id(node)] = min(total, MAX_EXPANDED_NODES + 1)
    return sizes[id(root)]


def parse_yaml(text: str) -> Any:
    """The document in ``text``: safe, keys unique, aliases bounded.

    Raises
    ------
    YamlFileError
        On a syntax error, a duplicate key, a document too large once its aliases are
        expanded, or one nested too deeply.
    """
    try:
        loader = _StrictLoader(text)
    except yaml.YAMLError as exc:  # a character YAML does not allow, seen on reading
        raise YamlFileError(str(exc).replace("\n", " ")) from None
    try:
        node = loader.get_single_node()
        if node is None:
            return None
        if expanded_size(node) > MAX_EXPANDED_NODES:
            raise YamlFileError(
                f"an alias bomb: over {MAX_EXPANDED_NODES} nodes with its aliases expanded"
            )
        return loader.construct_document(node)
    except yaml.MarkedYAMLError as exc:
        mark = exc.problem_mark or exc.context_mark
        reason = exc.problem or exc.context or "syntax error"
        if exc.problem and exc.context and exc.context_mark is not None:
            start = exc.context_mark
            reason += f" ({exc.context} at line {start.line + 1}, column {start.column + 1})"
        line = mark.line + 1 if mark is not None else 1
        column = mark.column + 1 if mark is not None else None
        raise YamlFileError(reason, line, column) from None
    except yaml.YAMLError as exc:
        raise YamlFileError(str(exc)) from None
    except RecursionError:
        raise YamlFileError("YAML nested too deeply") from None
    except YamlFileError:
        raise
    except ValueError as exc:  # an integer of more digits than Python converts
        raise YamlFileError(f"a number it cannot read: {exc}".split(";")[0]) from None
    finally:
        loader.dispose()


def read_bounded(path: Path) -> bytes:
    """The bytes of ``path``, a regular file of at most :data:`MAX_FILE_BYTES`.

    Raises
    ------
    YamlFileError
        If it is not a regular file (a folder, a device, a pipe) or is too large.
    OSError
        If it cannot be read.
    """
    if path.is_dir():
        raise YamlFileError("a folder")
    if path.exists() and not path.is_file():
        raise YamlFileError("not a regular file")
    size = path.stat().st_size
    if size > MAX_FILE_BYTES:
        raise YamlFileError(f"{size} bytes, over the limit of {MAX_FILE_BYTES}")
    with open(path, "rb") as fh:
        data = fh.read(MAX_FILE_BYTES + 1)
    if len(data) > MAX_FILE_BYTES:
        raise YamlFileError(f"over the limit of {MAX_FILE_BYTES} bytes")
    return data


_SHOWN = reprlib.Repr()
_SHOWN.maxlevel = 3
_SHOWN.maxlist = _SHOWN.maxtuple = _SHOWN.maxdict = _SHOWN.maxset = 6
_SHOWN.maxstring = 60
_SHOWN.maxother = 60
_SHOWN.maxlong = 40


def shown(value: Any) -> str:
    """A received value for an error message: a repr cut by depth, items and length."""
    return _SHOWN.repr(value)
