"""BT.CPP v4 port syntax the py_trees parser lacks, rewritten into what it builds:

* ``port="{=}"``: the key of the port's own name, ``{port}``;
* ``_autoremap="true"`` on a ``<SubTree>``: every key the subtree uses (and has not been
  remapped explicitly) is remapped to the caller's key of the same name;
* ``{@key}``: the root blackboard's ``/key`` from any depth. Each such key is renamed
  ``{ROOT__key}`` and passed down explicitly: the main ``<BehaviorTree>`` maps it to ``{key}``
  (its ``/key``) and every ``<SubTree>`` whose tree uses it, at any depth, passes it on;
* SubTree port defaults declared in ``<TreeNodesModel><SubTree ID=..><input_port name=..
  default=..>``: a port the ``<SubTree>`` does not give takes the default (as py_trees takes
  a ``<BehaviorTree>``'s own attributes as defaults).

It also parses, at validate time, the scripts of ``Script``/``ScriptCondition``/``Precondition``
and of the pre/post-condition attributes (a problem names the column in the script).
"""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET
from collections.abc import Callable

from planner.bt_script import Script, ScriptError, parse_script

__all__ = [
    "CONDITION_ATTRIBUTES",
    "ROOT_PREFIX",
    "parse_attribute_script",
    "rewrite_port_syntax",
    "script_keys",
    "translate_script_node",
    "underscore_problem",
]

#: The name a ``{@key}`` is passed down under.
ROOT_PREFIX = "ROOT__"
_KEY = re.compile(r"^\{(@?)([^{}]*)\}$")


def _trees(root: ET.Element) -> dict[str, ET.Element]:
    index: dict[str, ET.Element] = {}
    for bt in root.findall("BehaviorTree"):
        index.setdefault(bt.attrib.get("ID", ""), bt)
    return index


def _keys_used(bt: ET.Element) -> set[str]:
    """Keys named ``{key}`` in a tree's attributes (not the tree's own) and in its scripts."""
    keys: set[str] = set()
    for elem in bt.iter():
        if elem is bt:
            continue
        for value in elem.attrib.values():
            match = _KEY.match(value)
            if match and not match.group(1) and match.group(2):
                keys.add(match.group(2))
        keys |= script_keys(elem)
    return keys


#: Attributes of the script nodes holding a script (Precondition's ``if`` as the reader names it).
SCRIPT_CODE_ATTRIBUTES = {"Script": "code", "ScriptCondition": "code", "Precondition": "condition"}


def script_keys(elem: ET.Element) -> set[str]:
    """The keys (not ``@`` root keys) an element's scripts read or write: a script node's code
    and its pre/post-condition attributes. A script that does not parse has none (the reader
    reports it)."""
    scripts = list(getattr(elem, "conditions", {}).values())
    attr = SCRIPT_CODE_ATTRIBUTES.get(elem.tag)
    if attr is not None and attr in elem.attrib:
        try:
            scripts.append(parse_script(elem.attrib[attr]))
        except ScriptError:
            pass
    return {
        key
        for script in scripts
        for key in script.keys_read() | script.keys_written()
        if not key.startswith("@")
    }


def rewrite_port_syntax(root: ET.Element, main_id: str | None) -> None:
    """Rewrite ``{=}``, ``{@key}``, ``_autoremap`` and model defaults in place (see module)."""
    trees = _trees(root)
    root_keys: set[str] = set()
    for bt in trees.values():
        for elem in bt.iter():
            for name, value in list(elem.attrib.items()):
                if value == "{=}":
                    elem.attrib[name] = "{" + name + "}"
                match = _KEY.match(elem.attrib[name])
                if match and match.group(1):
                    root_keys.add(match.group(2))
                    elem.attrib[name] = "{" + ROOT_PREFIX + match.group(2) + "}"
    _model_defaults(root, trees)
    # Which root keys each tree needs, through its subtrees too (fixed point; cycles are
    # reported by the checker).
    needs = {
        bt_id: {k[len(ROOT_PREFIX) :] for k in _keys_used(bt) if k.startswith(ROOT_PREFIX)}
        for bt_id, bt in trees.items()
    }
    changed = True
    while changed:
        changed = False
        for bt_id, bt in trees.items():
            for sub in bt.iter("SubTree"):
                more = needs.get(sub.attrib.get("ID", ""), set()) - needs[bt_id]
                if more:
                    needs[bt_id] |= more
                    changed = True
    for bt in trees.values():
        for sub in bt.iter("SubTree"):
            target = sub.attrib.get("ID", "")
            if target not in trees:
                continue
            for key in sorted(needs[target]):
                sub.attrib.setdefault(ROOT_PREFIX + key, "{" + ROOT_PREFIX + key + "}")
    _autoremap(trees)
    if main_id in trees and root_keys:
        for key in sorted(needs[str(main_id)]):
            trees[str(main_id)].attrib.setdefault(ROOT_PREFIX + key, "{" + key + "}")


def _autoremap(trees: dict[str, ET.Element]) -> None:
    """Give every ``_autoremap`` ``<SubTree>`` each key its tree uses as the caller's key of the
    same name, through nested subtrees: a key an inner tree reads is passed by an autoremapped
    middle tree that never names it (BT.CPP looks a key up through every autoremapping parent).
    A key passed on becomes one the passing tree uses, so this runs to a fixed point."""
    changed = True
    while changed:
        changed = False
        for bt in trees.values():
            for sub in bt.iter("SubTree"):
                target = trees.get(sub.attrib.get("ID", ""))
                if target is None or not getattr(sub, "autoremap", False):
                    continue
                for key in sorted(_keys_used(target) - sub.attrib.keys()):
                    sub.attrib[key] = "{" + key + "}"
                    changed = True


def _model_defaults(root: ET.Element, trees: dict[str, ET.Element]) -> None:
    """Copy ``<TreeNodesModel><SubTree>`` port defaults onto the ``<BehaviorTree>``; note
    the ports it declares (``model_ports``) as ports a ``<SubTree>`` may give."""
    for model in root.findall("TreeNodesModel"):
        for entry in model.findall("SubTree"):
            bt = trees.get(entry.attrib.get("ID", ""))
            if bt is None:
                continue
            declared: set[str] = set()
            for port in entry:
                name, default = port.attrib.get("name"), port.attrib.get("default")
                if port.tag.endswith("_port") and name:
                    declared.add(name)
                    if default is not None:
                        bt.attrib.setdefault(name, default)
            bt.model_ports = declared  # type: ignore[attr-defined]


#: BT.CPP's pre-conditions (checked before a tick) and post-conditions (run after it).
CONDITION_ATTRIBUTES = (
    "_failureIf",
    "_successIf",
    "_skipIf",
    "_while",
    "_onSuccess",
    "_onFailure",
    "_onHalted",
    "_post",
)


def parse_attribute_script(
    source: str, attribute: str, problem: Callable[[str], None]
) -> Script | None:
    """Parse a script attribute at validate time; a problem names its column."""
    try:
        return parse_script(source)
    except ScriptError as exc:
        problem(f"attribute '{attribute}': column {exc.column} in the script: {exc.reason}")
        return None


def translate_script_node(elem: ET.Element, problem: Callable[[str], None]) -> None:
    """Check the script of Script/ScriptCondition/Precondition; name Precondition's
    ``if``/``else`` (Python keywords) ``condition``/``otherwise``."""
    tag = (
        elem.attrib.get("ID", elem.tag)
        if elem.tag in ("Action", "Condition", "Decorator")
        else elem.tag
    )
    if tag in ("Script", "ScriptCondition") and "code" in elem.attrib:
        parse_attribute_script(elem.attrib["code"], "code", problem)
    elif tag == "Precondition":
        if "if" in elem.attrib:
            elem.attrib["condition"] = elem.attrib.pop("if")
            parse_attribute_script(elem.attrib["condition"], "if", problem)
        if "else" in elem.attrib:
            elem.attrib["otherwise"] = elem.attrib.pop("else")
            if elem.attrib["otherwise"] not in ("SUCCESS", "FAILURE", "RUNNING"):
                problem(
                    "attribute 'else': expected SUCCESS, FAILURE or RUNNING, got "
                    f"'{elem.attrib['otherwise'][:40]}'"
                )


def underscore_problem(key: str) -> str:
    """What to say about a ``_``-attribute the loader cannot honour."""
    if key == "_autoremap":
        return "attribute '_autoremap': expected true or false (or 1 or 0)"
    return (
        f"unknown attribute '{key}'; expected one of the BT.CPP attributes "
        f"{', '.join(CONDITION_ATTRIBUTES)}, _autoremap, _description"
    )
