"""Render ranked actions for people (text) and for tools (JSON with a fixed key order)."""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from typing import Any

from affordances.actions import ParamValue, SemanticAction, SkillSelection

#: Decimal places kept for numbers in the JSON output.
JSON_DECIMALS = 4

Results = Mapping[str, Sequence[SemanticAction]]


def _json_value(value: ParamValue) -> Any:
    if isinstance(value, float):
        return round(value, JSON_DECIMALS)
    if isinstance(value, tuple):
        return list(value)
    return value


def skill_to_dict(skill: SkillSelection) -> dict[str, Any]:
    """One skill as ``{"action", "space", "weight", "params"}`` (params keys sorted)."""
    return {
        "action": skill.action.value,
        "space": skill.space.value,
        "weight": round(skill.weight, JSON_DECIMALS),
        "params": {key: _json_value(skill.params[key]) for key in sorted(skill.params)},
    }


def action_to_dict(action: SemanticAction) -> dict[str, Any]:
    """One action as ``{"grasp", "skills", "score", "because"}``."""
    return {
        "grasp": action.grasp.value,
        "skills": [skill_to_dict(s) for s in action.skills],
        "score": round(action.score, JSON_DECIMALS),
        "because": list(action.because),
    }


def to_json_data(results: Results) -> dict[str, Any]:
    """``{"objects": [{"name", "actions": [...]}]}`` in the order of ``results``."""
    return {
        "objects": [
            {"name": name, "actions": [action_to_dict(a) for a in actions]}
            for name, actions in results.items()
        ]
    }


def render_json(results: Results, indent: int | None = 2) -> str:
    """JSON text of :func:`to_json_data`; the same results always give the same text."""
    return json.dumps(to_json_data(results), indent=indent, ensure_ascii=False, allow_nan=False)


def _show_param(value: ParamValue) -> str:
    if isinstance(value, float):
        return f"{value:.3g}"
    if isinstance(value, tuple):
        return ",".join(value)
    return value


def _show_skill(skill: SkillSelection) -> str:
    params = ", ".join(f"{k}={_show_param(v)}" for k, v in sorted(skill.params.items()))
    head = f"{skill.action.value} [{skill.space.value}, w={skill.weight:g}]"
    return f"{head} {params}" if params else head


def render_text(results: Results) -> str:
    """A plain-text report: per object, each action with its skills and reasons."""
    lines: list[str] = []
    for name, actions in results.items():
        lines.append(f"{name}")
        for rank, action in enumerate(actions, start=1):
            lines.append(f"  {rank}. {action.grasp.value}  (score {action.score:g})")
            for skill in action.skills:
                lines.append(f"       skill  {_show_skill(skill)}")
            for reason in action.because:
                lines.append(f"       because {reason}")
        lines.append("")
    return "\n".join(lines)
