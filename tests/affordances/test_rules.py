"""Rule files: the default file loads, matching works, and bad files say what is wrong."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
import yaml

from affordances import RuleFileError, default_rules, load_rules, parse_rules
from affordances.rules import Condition, Fact, GraspEffect, Op, ParamEffect, SkillEffect
from skills.vocabulary import Action, GraspType, Space


def _rule(**fields: Any) -> dict[str, Any]:
    rule: dict[str, Any] = {"name": "r", "effects": [{"grasp": "two_palm_lateral", "weight": 1}]}
    rule.update(fields)
    return rule


def _doc(*rules: dict[str, Any]) -> dict[str, Any]:
    return {"version": 1, "rules": list(rules)}


def test_default_rules_load() -> None:
    rules = default_rules()
    assert rules[0].name == "default_speed"
    assert {r.name for r in rules} >= {"parcel_lateral", "tray_support", "fragile_careful"}
    assert all(r.source == "affordances/rulesets/default.yaml" for r in rules)


def test_parse_forms() -> None:
    (rule,) = parse_rules(
        _doc(
            {
                "name": "all_forms",
                "when": {
                    "category": "Parcel",
                    "material": ["glass", "ceramic"],
                    "mass_kg": {"gt": 2, "le": 10.5},
                    "state": {"contains": "open"},
                    "elements": ["wide", "heavy"],
                },
                "effects": [
                    {"grasp": "two_arm_support", "weight": 2},
                    {"skill": "keep_level", "weight": 0.5, "space": "absolute", "params": {"k": 3}},
                    {"param": "max_speed", "value": 0.2},
                    {"param": "stiffness", "value": 100, "skill": "hold_force"},
                ],
            }
        ),
        "test",
    )
    assert rule.conditions == (
        Condition(Fact.CATEGORY, Op.EQ, "parcel"),
        Condition(Fact.MATERIAL, Op.IN, ("glass", "ceramic")),
        Condition(Fact.MASS_KG, Op.GT, 2.0),
        Condition(Fact.MASS_KG, Op.LE, 10.5),
        Condition(Fact.STATE, Op.CONTAINS, "open"),
        Condition(Fact.ELEMENTS, Op.CONTAINS, ("wide", "heavy")),
    )
    assert rule.effects[0] == GraspEffect(GraspType.TWO_ARM_SUPPORT, 2.0)
    skill = rule.effects[1]
    assert isinstance(skill, SkillEffect)
    assert (skill.action, skill.space, skill.weight, dict(skill.params)) == (
        Action.KEEP_LEVEL,
        Space.ABSOLUTE,
        0.5,
        {"k": 3.0},
    )
    assert rule.effects[2] == ParamEffect("max_speed", 0.2, Action.TRANSPORT)
    assert rule.effects[3] == ParamEffect("stiffness", 100.0, Action.HOLD_FORCE)


@pytest.mark.parametrize(
    ("facts", "expected"),
    [
        ({Fact.MASS_KG: 3.0, Fact.ELEMENTS: frozenset({"wide", "heavy", "light"})}, True),
        ({Fact.MASS_KG: 2.0, Fact.ELEMENTS: frozenset({"wide", "heavy"})}, False),
        ({Fact.MASS_KG: 3.0, Fact.ELEMENTS: frozenset({"wide"})}, False),
        ({Fact.ELEMENTS: frozenset({"wide", "heavy"})}, False),
    ],
)
def test_matching(facts: dict[Fact, Any], expected: bool) -> None:
    when = {"mass_kg": {"gt": 2}, "elements": ["wide", "heavy"]}
    (rule,) = parse_rules(_doc(_rule(when=when)), "t")
    assert rule.matches(facts) is expected


def test_set_operators() -> None:
    (rule,) = parse_rules(
        _doc(_rule(when={"state": {"contains_any": ["open", "full"], "excludes": "hot"}})), "t"
    )
    assert rule.matches({Fact.STATE: frozenset({"full"})})
    assert not rule.matches({Fact.STATE: frozenset({"full", "hot"})})
    assert not rule.matches({Fact.STATE: frozenset()})
    assert rule.describe({Fact.STATE: frozenset({"full"})}) == (
        "state contains any of open, full, state excludes hot"
    )


BAD = [
    ({"version": 2, "rules": []}, r"f\.yaml: field 'version': expected 1, got 2"),
    ({"version": 1, "rulez": []}, r"f\.yaml: field 'rulez': unknown key"),
    (_doc(_rule(name="")), r"rule 0: field 'name': expected a non-empty string"),
    (_doc(_rule(), _rule()), r"rule 1 \('r'\): field 'name': duplicate rule name"),
    (_doc(_rule(wen={})), r"rule 0 \('r'\): field 'wen': unknown key"),
    (_doc(_rule(when={"colour": "red"})), r"rule 0 \('r'\): field 'when\.colour': unknown fact"),
    (
        _doc(_rule(when={"mass_kg": {"greater": 2}})),
        r"rule 0 \('r'\): field 'when\.mass_kg': bad operator 'greater' for a number fact",
    ),
    (
        _doc(_rule(when={"category": {"gt": 2}})),
        r"field 'when\.category': bad operator 'gt' for a text fact",
    ),
    (_doc(_rule(when={"mass_kg": {"gt": "two"}})), r"field 'when\.mass_kg\.gt': expected a number"),
    (_doc(_rule(when={"state": "wet"})), r"field 'when\.state': unknown ObjectState 'wet'"),
    (
        _doc(_rule(when={"elements": ["wide", "huge"]})),
        r"field 'when\.elements\[1\]': unknown AffordanceElement 'huge'",
    ),
    (_doc(_rule(effects=[])), r"field 'effects': expected a non-empty list"),
    (
        _doc(_rule(effects=[{"skill": "juggle", "weight": 1}])),
        r"rule 0 \('r'\): field 'effects\[0\]\.skill': unknown Action 'juggle'",
    ),
    (
        _doc(_rule(effects=[{"grasp": "pinch", "weight": 1}])),
        r"field 'effects\[0\]\.grasp': unknown GraspType 'pinch'",
    ),
    (
        _doc(_rule(effects=[{"grasp": "two_arm_support", "weight": "lots"}])),
        r"rule 0 \('r'\): field 'effects\[0\]\.weight': expected a number, got 'lots'",
    ),
    (
        _doc(_rule(effects=[{"grasp": "two_arm_support", "weight": True}])),
        r"field 'effects\[0\]\.weight': expected a number, got True",
    ),
    (
        _doc(_rule(effects=[{"grasp": "two_arm_support", "weight": float("nan")}])),
        r"field 'effects\[0\]\.weight': expected a finite number",
    ),
    (_doc(_rule(effects=[{"grasp": "two_arm_support"}])), r"field 'effects\[0\]\.weight': missing"),
    (
        _doc(_rule(effects=[{"grasp": "two_arm_support", "weight": 1, "colour": "red"}])),
        r"field 'effects\[0\]\.colour': unknown key",
    ),
    (
        _doc(_rule(effects=[{"param": "stiffness", "value": 3}])),
        r"field 'effects\[0\]\.skill': missing; 'stiffness' is not one of",
    ),
    (
        _doc(_rule(effects=[{"param": "max_speed", "value": [1, 2]}])),
        r"field 'effects\[0\]\.value': expected a number",
    ),
    (
        _doc(_rule(effects=[{"skill": "transport", "space": "sideways"}])),
        r"field 'effects\[0\]\.space': unknown Space 'sideways'",
    ),
    (_doc(_rule(effects=[{"weight": 1}])), r"field 'effects\[0\]': expected exactly one of"),
    (
        _doc(_rule(effects=[{"grasp": "two_arm_support", "veto": False}])),
        r"field 'effects\[0\]\.veto': expected true, got False",
    ),
    (
        _doc(_rule(effects=[{"grasp": "two_arm_support", "veto": True, "weight": 1}])),
        r"field 'effects\[0\]\.weight': a vetoed grasp has no weight",
    ),
    ("just text", r"f\.yaml: field '': expected a mapping with 'version' and 'rules'"),
]


@pytest.mark.parametrize(("doc", "match"), BAD)
def test_bad_rule_file_names_file_rule_and_field(doc: Any, match: str, tmp_path: Path) -> None:
    path = tmp_path / "f.yaml"
    path.write_text(yaml.safe_dump(doc), encoding="utf-8")
    with pytest.raises(RuleFileError, match=match):
        load_rules(path)


def test_second_rule_error_names_its_index_and_name(tmp_path: Path) -> None:
    path = tmp_path / "user.yaml"
    path.write_text(
        "version: 1\n"
        "rules:\n"
        "  - name: fine\n"
        "    effects: [{grasp: one_arm_side, weight: 1}]\n"
        "  - name: broken\n"
        "    when: {mass_kg: {gt: heavy}}\n"
        "    effects: [{grasp: one_arm_side, weight: 1}]\n",
        encoding="utf-8",
    )
    with pytest.raises(
        RuleFileError,
        match=r"user\.yaml: rule 1 \('broken'\): field 'when\.mass_kg\.gt': expected a number, "
        r"got 'heavy'",
    ):
        load_rules(path)


def test_unreadable_and_invalid_yaml(tmp_path: Path) -> None:
    with pytest.raises(RuleFileError, match=r"missing\.yaml: cannot read"):
        load_rules(tmp_path / "missing.yaml")
    path = tmp_path / "broken.yaml"
    path.write_text("rules: [\n", encoding="utf-8")
    with pytest.raises(RuleFileError, match=r"broken\.yaml:2:1: not valid YAML"):
        load_rules(path)
