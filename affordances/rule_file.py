"""Reading rule files: YAML checked field by field into :mod:`affordances.rules`' rules, each
error naming the file, the rule and the field; the shipped file and the user's in order.

The format is :mod:`affordances.rules`' docstring.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from enum import StrEnum
from functools import lru_cache
from importlib import resources
from pathlib import Path
from types import MappingProxyType
from typing import Any

import yaml

from affordances.actions import DEFAULT_SPACE, ParamValue
from affordances.rules import (
    FACT_KINDS,
    KIND_OPS,
    PARAM_RANGES,
    PARAM_SKILLS,
    Condition,
    Effect,
    Fact,
    FactKind,
    GraspEffect,
    Op,
    ParamEffect,
    Rule,
    SkillEffect,
)
from affordances.safe_yaml import YamlFileError, parse_yaml, read_bounded, shown
from skills.vocabulary import Action, GraspType, Space

#: File the package ships; used unless the caller leaves it out.
DEFAULT_RULES_FILE = "default.yaml"


SUPPORTED_VERSION = 1


class RuleFileError(ValueError):
    """A rule file is malformed; the message names the file, the rule and the field."""


_RULE_KEYS = ("name", "description", "when", "effects")


_EFFECT_KEYS = {
    "grasp": ("grasp", "weight", "veto"),
    "skill": ("skill", "weight", "space", "params"),
    "param": ("param", "value", "skill"),
}


class _Where:
    """Builds error messages naming the file, the rule and the field."""

    def __init__(self, source: str, index: int | None = None, name: str | None = None) -> None:
        self.source, self.index, self.name = source, index, name

    def error(self, field: str, message: str) -> RuleFileError:
        where = self.source
        if self.index is not None:
            where += f": rule {self.index}"
            if self.name is not None:
                where += f" ({shown(self.name)})"
        return RuleFileError(f"{where}: field {shown(field)}: {message}")


#: Largest magnitude any number in a rule file may have: beyond what a mass, a size, a speed
#: or a weight can mean (and a 400-digit integer would not even convert to a float).
MAX_MAGNITUDE = 1e9


def _number(value: Any, where: _Where, field: str) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise where.error(field, f"expected a number, got {shown(value)}")
    finite = abs(value) <= MAX_MAGNITUDE if isinstance(value, int) else math.isfinite(value)
    if not finite or abs(float(value)) > MAX_MAGNITUDE:
        raise where.error(
            field, f"expected a finite number within +-{MAX_MAGNITUDE:g}, got {shown(value)}"
        )
    return float(value)


def _member(value: Any, enum_cls: type[StrEnum], where: _Where, field: str) -> str:
    if not isinstance(value, str) or value not in {m.value for m in enum_cls}:
        allowed = ", ".join(m.value for m in enum_cls)
        raise where.error(
            field, f"unknown {enum_cls.__name__} {shown(value)}; expected one of {allowed}"
        )
    return value


def _operand(
    value: Any, fact: Fact, op: Op, where: _Where, field: str
) -> float | str | tuple[Any, ...]:
    kind, enum_cls = FACT_KINDS[fact]
    many = op in (Op.IN, Op.NOT_IN, Op.CONTAINS_ANY) or (
        op in (Op.CONTAINS, Op.EXCLUDES) and isinstance(value, list)
    )
    if many:
        if not isinstance(value, list) or not value:
            raise where.error(
                field, f"expected a non-empty list for {op.value!r}, got {shown(value)}"
            )
        return tuple(
            _scalar(v, kind, enum_cls, where, f"{field}[{i}]") for i, v in enumerate(value)
        )
    if isinstance(value, list | dict):
        raise where.error(field, f"expected a single value for {op.value!r}, got {shown(value)}")
    return _scalar(value, kind, enum_cls, where, field)


def _scalar(
    value: Any, kind: FactKind, enum_cls: type[StrEnum] | None, where: _Where, field: str
) -> float | str:
    if kind == FactKind.NUMBER:
        return _number(value, where, field)
    if enum_cls is not None:
        return _member(value, enum_cls, where, field)
    if not isinstance(value, str) or not value.strip():
        raise where.error(field, f"expected a non-empty string, got {shown(value)}")
    return value.strip().lower()


def _conditions(when: Any, where: _Where) -> tuple[Condition, ...]:
    if when is None:
        return ()
    if not isinstance(when, dict):
        raise where.error("when", f"expected a mapping of facts, got {shown(when)}")
    conditions: list[Condition] = []
    for key, spec in when.items():
        field = f"when.{key}"
        if key not in {f.value for f in Fact}:
            raise where.error(
                field,
                f"unknown fact {shown(key)}; expected one of {', '.join(f.value for f in Fact)}",
            )
        fact = Fact(key)
        kind = FACT_KINDS[fact][0]
        allowed = KIND_OPS[kind]
        if isinstance(spec, dict):
            if not spec:
                raise where.error(field, "expected at least one operator")
            for op_name, operand in spec.items():
                if op_name not in {o.value for o in allowed}:
                    raise where.error(
                        field,
                        f"bad operator {shown(op_name)} for a {kind.value} fact; expected one of "
                        f"{', '.join(o.value for o in allowed)}",
                    )
                op = Op(op_name)
                conditions.append(
                    Condition(fact, op, _operand(operand, fact, op, where, f"{field}.{op_name}"))
                )
        else:
            if kind == FactKind.SET:
                op = Op.CONTAINS
            else:
                op = Op.IN if isinstance(spec, list) else Op.EQ
            conditions.append(Condition(fact, op, _operand(spec, fact, op, where, field)))
    return tuple(conditions)


def _check_keys(item: dict[str, Any], allowed: Sequence[str], where: _Where, field: str) -> None:
    unknown = sorted(set(item) - set(allowed))
    if unknown:
        raise where.error(
            f"{field}.{unknown[0]}" if field else unknown[0],
            f"unknown key; expected one of {', '.join(allowed)}",
        )


def _params(value: Any, where: _Where, field: str) -> dict[str, ParamValue]:
    if value is None:
        return {}
    if not isinstance(value, dict):
        raise where.error(field, f"expected a mapping, got {shown(value)}")
    params: dict[str, ParamValue] = {}
    for key, item in value.items():
        if not isinstance(key, str):
            raise where.error(field, f"expected string keys, got {shown(key)}")
        params[key] = _param_value(item, where, f"{field}.{key}", key)
    return params


def _param_value(value: Any, where: _Where, field: str, name: str) -> float | str:
    """A parameter's value; a known parameter (:data:`PARAM_RANGES`) must be in its range."""
    if isinstance(value, str) and name not in PARAM_RANGES:
        return value
    number = _number(value, where, field)
    if name in PARAM_RANGES:
        low, high, unit, open_low = PARAM_RANGES[name]
        above = number > low if open_low else number >= low
        if not (above and number <= high):
            left = "(" if open_low else "["
            units = f" {unit}" if unit else ""
            raise where.error(
                field, f"expected {name} in {left}{low:g}, {high:g}]{units}, got {shown(value)}"
            )
    return number


def _effect(item: Any, where: _Where, field: str) -> Effect:
    if not isinstance(item, dict):
        raise where.error(field, f"expected a mapping, got {shown(item)}")
    kinds = [k for k in ("param", "grasp") if k in item] or (["skill"] if "skill" in item else [])
    if len(kinds) != 1:
        raise where.error(
            field, f"expected exactly one of 'grasp', 'skill' or 'param', got keys {sorted(item)}"
        )
    kind = kinds[0]
    _check_keys(item, _EFFECT_KEYS[kind], where, field)
    if kind == "grasp":
        grasp = GraspType(_member(item["grasp"], GraspType, where, f"{field}.grasp"))
        if "veto" in item:
            if item["veto"] is not True:
                raise where.error(f"{field}.veto", f"expected true, got {item['veto']!r}")
            if "weight" in item:
                raise where.error(f"{field}.weight", "a vetoed grasp has no weight")
            return GraspEffect(grasp, 0.0, veto=True)
        if "weight" not in item:
            raise where.error(
                f"{field}.weight", "missing; a grasp effect needs a weight (or veto: true)"
            )
        return GraspEffect(grasp, _number(item["weight"], where, f"{field}.weight"))
    if kind == "skill":
        action = Action(_member(item["skill"], Action, where, f"{field}.skill"))
        space = DEFAULT_SPACE[action]
        if "space" in item:
            space = Space(_member(item["space"], Space, where, f"{field}.space"))
        weight = _number(item.get("weight", 1.0), where, f"{field}.weight")
        return SkillEffect(
            action,
            space,
            weight,
            MappingProxyType(_params(item.get("params"), where, f"{field}.params")),
        )
    name = item["param"]
    if not isinstance(name, str) or not name:
        raise where.error(f"{field}.param", f"expected a parameter name, got {shown(name)}")
    if "value" not in item:
        raise where.error(f"{field}.value", "missing; a param effect needs a value")
    value = _param_value(item["value"], where, f"{field}.value", name)
    if "skill" in item:
        action = Action(_member(item["skill"], Action, where, f"{field}.skill"))
    elif name in PARAM_SKILLS:
        action = PARAM_SKILLS[name]
    else:
        raise where.error(
            f"{field}.skill",
            f"missing; {shown(name)} is not one of {', '.join(PARAM_SKILLS)}, so name its skill",
        )
    return ParamEffect(name, value, action)


def parse_rules(data: Any, source: str) -> tuple[Rule, ...]:
    """Validate a loaded rule document and build its rules.

    Parameters
    ----------
    data : Any
        The document as ``yaml.safe_load`` returns it.
    source : str
        File name (or label) used in error messages and kept on each rule.

    Returns
    -------
    tuple of Rule
        In file order.

    Raises
    ------
    RuleFileError
        Naming the file, the rule (index and name) and the field.
    """
    top = _Where(source)
    if not isinstance(data, dict):
        raise top.error(
            "", f"expected a mapping with 'version' and 'rules', got {type(data).__name__}"
        )
    _check_keys(data, ("version", "rules"), top, "")
    if data.get("version") != SUPPORTED_VERSION:
        raise top.error(
            "version", f"expected {SUPPORTED_VERSION}, got {shown(data.get('version'))}"
        )
    items = data.get("rules")
    if not isinstance(items, list):
        raise top.error("rules", f"expected a list of rules, got {shown(items)}")
    rules: list[Rule] = []
    seen: set[str] = set()
    for index, item in enumerate(items):
        where = _Where(source, index)
        if not isinstance(item, dict):
            raise where.error("", f"expected a mapping, got {shown(item)}")
        name = item.get("name")
        if not isinstance(name, str) or not name.strip():
            raise where.error("name", f"expected a non-empty string, got {shown(name)}")
        where = _Where(source, index, name)
        if name in seen:
            raise where.error("name", "duplicate rule name")
        seen.add(name)
        _check_keys(item, _RULE_KEYS, where, "")
        description = item.get("description", "")
        if not isinstance(description, str):
            raise where.error("description", f"expected a string, got {description!r}")
        effects = item.get("effects")
        if not isinstance(effects, list) or not effects:
            raise where.error("effects", f"expected a non-empty list, got {effects!r}")
        rules.append(
            Rule(
                name=name,
                conditions=_conditions(item.get("when"), where),
                effects=tuple(_effect(e, where, f"effects[{i}]") for i, e in enumerate(effects)),
                source=source,
                description=description,
            )
        )
    return tuple(rules)


def load_rules(path: str | Path) -> tuple[Rule, ...]:
    """Read and validate one rule file.

    Raises
    ------
    RuleFileError
        If the file is not valid YAML or not a valid rule file; names the file.
    """
    path = Path(path)
    try:
        text = read_bounded(path).decode("utf-8-sig")
    except YamlFileError as err:
        raise RuleFileError(f"{path}: expected a YAML rule file, got {err.problem}") from None
    except UnicodeDecodeError as err:
        raise RuleFileError(f"{path}: byte {err.start} is not UTF-8") from None
    except OSError as err:
        raise RuleFileError(f"{path}: cannot read: {err.strerror or err}") from None
    try:
        data = parse_yaml(text)
    except YamlFileError as err:
        where = f":{err.line}" + (f":{err.column}" if err.column else "") if err.line else ""
        raise RuleFileError(f"{path}{where}: not valid YAML: {err.problem}") from None
    return parse_rules(data, str(path))


@lru_cache(maxsize=1)
def default_rules() -> tuple[Rule, ...]:
    """The rules shipped in ``affordances/rulesets/default.yaml``."""
    text = (
        resources.files("affordances")
        .joinpath("rulesets", DEFAULT_RULES_FILE)
        .read_text(encoding="utf-8")
    )
    return parse_rules(yaml.safe_load(text), f"affordances/rulesets/{DEFAULT_RULES_FILE}")


def rule_set(paths: Sequence[str | Path] = (), *, include_default: bool = True) -> tuple[Rule, ...]:
    """The default rules (unless left out) followed by the rules of each file, in order.

    Later rules win when they set the same parameter, so user files refine the defaults.
    """
    rules: list[Rule] = list(default_rules()) if include_default else []
    for path in paths:
        rules.extend(load_rules(path))
    return tuple(rules)


__all__ = [
    "DEFAULT_RULES_FILE",
    "SUPPORTED_VERSION",
    "RuleFileError",
    "default_rules",
    "load_rules",
    "parse_rules",
    "rule_set",
]
