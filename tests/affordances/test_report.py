"""Text and JSON renderings of ranked actions."""

from __future__ import annotations

import json

from affordances import reason, render_json, render_text, to_json_data
from tests.affordances.cases import ROBOT, parcel, tray


def test_json_shape_and_key_order() -> None:
    results = {"parcel": reason(parcel(goal_yaw=0.5), ROBOT), "tray": reason(tray(), ROBOT)}
    data = json.loads(render_json(results))
    assert list(data) == ["objects"]
    assert [o["name"] for o in data["objects"]] == ["parcel", "tray"]
    obj = data["objects"][0]
    assert list(obj) == ["name", "actions"]
    top = obj["actions"][0]
    assert list(top) == ["grasp", "skills", "score", "because"]
    assert top["grasp"] == "two_palm_lateral"
    assert top["score"] == 3.0
    actions = [s["action"] for s in top["skills"]]
    assert actions == ["transport", "rotate_z", "limit_repulsion", "hold_lateral"]
    hold = top["skills"][actions.index("hold_lateral")]
    assert list(hold) == ["action", "space", "weight", "params"]
    assert hold["space"] == "relative"
    assert hold["params"] == {
        "required_force_n": 11.4961,
        "span_m": 0.3,
        "squeeze_axis": "y",
        "squeeze_force_n": 11.4961,
    }
    assert top["skills"][0]["params"]["arms"] == ["left", "right"]
    assert "rule parcel_lateral (+2): category parcel" in top["because"]
    assert to_json_data(results) == data


def test_json_is_deterministic() -> None:
    results = {"parcel": reason(parcel(), ROBOT)}
    assert render_json(results) == render_json({"parcel": reason(parcel(), ROBOT)})


def test_text_report_lists_ranks_skills_and_reasons() -> None:
    text = render_text({"parcel": reason(parcel(), ROBOT)})
    lines = text.splitlines()
    assert lines[0] == "parcel"
    assert lines[1] == "  1. two_palm_lateral  (score 3)"
    assert "       skill  hold_lateral [relative, w=1] required_force_n=11.5, span_m=0.3, " in text
    assert "       because rule parcel_lateral (+2): category parcel" in lines
    assert "  2. two_arm_support  (score 0)" in lines
