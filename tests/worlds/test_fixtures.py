"""The slot-insertion world: fixtures load, bad fixture fields are refused clearly, and the
fixture is built in PyBullet and FCL where the file says."""

from __future__ import annotations

import copy
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml
from numpy.testing import assert_allclose

from skills.insertion import grasp_height, max_wall_height
from worlds.world_file import WorldFileError, load_world, world_spec

REPO = Path(__file__).resolve().parents[2]
SLOT = REPO / "worlds" / "slot_insertion.yaml"


@pytest.fixture(scope="module")
def data() -> dict[str, Any]:
    loaded = yaml.safe_load(SLOT.read_text(encoding="utf-8"))
    assert isinstance(loaded, dict)
    loaded.pop("tree")  # relative to the file; these copies are validated from memory
    return loaded


def _refused(data: dict[str, Any], match: str, folder: Path) -> None:
    path = folder / "bad.yaml"
    path.write_text(yaml.safe_dump(data), encoding="utf-8")
    with pytest.raises(WorldFileError, match=match):
        load_world(path)


def test_slot_world_loads_with_a_fitting_fixture() -> None:
    world = load_world(SLOT)
    spec = world_spec(world)
    (fixture,) = spec.scene.fixtures
    assert fixture.for_object == "parcel"
    assert_allclose(fixture.inner, (0.21, 0.31))  # the parcel's footprint + 5 mm per side
    assert_allclose(fixture.position, (0.60, -0.18, 0.6))
    assert spec.task[0].moves[0].fixture == "slot"
    tree = world.tree_path()
    assert tree is not None and tree.resolve() == REPO / "planner" / "trees" / "slot_insertion.xml"


def test_walls_stay_below_the_palms_holding_the_seated_box() -> None:
    # Parcel 0.15 m tall, palms 0.12 m long, walls 4 cm: palm centres 3.5 cm up the faces,
    # their lower edges 1 cm above the walls; each still covers half its length of the face.
    dz = grasp_height(0.15, 0.12, 0.04)
    assert_allclose(dz, 0.035)
    assert_allclose((dz - 0.06 + 0.075) - 0.04, 0.01)  # palm bottom above the box bottom
    assert_allclose(max_wall_height(0.15, 0.12), 0.08)
    assert grasp_height(0.15, 0.12, 0.005) == 0.0  # low walls: the centred grasp clears them


@pytest.mark.parametrize(
    ("change", "match"),
    [
        (
            lambda d: d["fixtures"][0].update(wall_height=0.09),
            r"fixtures\[0\]\.wall_height.*at most 0\.080",
        ),
        (
            lambda d: d["fixtures"][0].update(for_object="crate"),
            r"fixtures\[0\]\.for_object.*box object",
        ),
        (lambda d: d["fixtures"][0].update(clearance=-0.005), r"fixtures\[0\]\.clearance"),
        (lambda d: d["fixtures"][0].update(position=[0.6]), r"fixtures\[0\]\.position.*2 numbers"),
        (
            lambda d: d["fixtures"][0].update(position=[0.6, 0.4]),
            r"fixtures\[0\]\.position.*table top",
        ),
        (lambda d: d["fixtures"][0].update(colour="red"), r"fixtures\[0\]\.colour"),
        (lambda d: d["task"][0]["moves"][0].update(fixture="hole"), r"moves\[0\]\.fixture.*'slot'"),
        (
            lambda d: d["task"][0]["moves"][0]["goal"].update(position=[0.6, -0.17, 0.675]),
            r"moves\[0\]\.goal.*seated in fixture 'slot'",
        ),
        (lambda d: d["trials"]["insertion"].update(fixture="hole"), r"trials\.insertion\.fixture"),
    ],
)
def test_bad_fixture_fields_are_refused_naming_the_field(
    data: dict[str, Any], change: Any, match: str, tmp_path: Path
) -> None:
    bad = copy.deepcopy(data)
    change(bad)
    _refused(bad, match, tmp_path)


def test_bad_fixture_file_exits_2_with_one_line(capsys: pytest.CaptureFixture[str]) -> None:
    from worlds.world_file import world_cli_validate

    path = REPO / "tests" / "data" / "bad_worlds" / "fixture_wall_too_high.yaml"
    assert world_cli_validate(str(path)) == 2
    err = capsys.readouterr().err
    assert "fixture_wall_too_high.yaml" in err and "fixtures[0].wall_height" in err


def test_a_world_without_fixtures_dumps_as_before() -> None:
    world = load_world(REPO / "worlds" / "parcel_pick_place.yaml")
    dumped = world.model_dump(mode="json")
    assert "fixtures" not in dumped
    assert "fixture" not in dumped["task"][0]["moves"][0]
    assert "insertion" not in dumped["trials"]


@pytest.mark.sim
def test_fixture_built_in_pybullet_and_fcl_where_the_file_says() -> None:
    from worlds.collision import FIXTURES
    from worlds.sim_world import SimWorld

    with SimWorld(load_world(SLOT)) as sim:
        sim.advance(0.1)
        # The parcel on the table, away from the fixture: no force, no wall pressed.
        assert_allclose(sim.fixture_force("parcel"), np.zeros(3))
        assert sim.fixture_log.forces("slot").shape[1] == 4
        assert not sim.fixture_log.robot_contacts
        names = [n for n in sim.collision.element_names if n.startswith("slot/")]
        assert names == ["slot/+x", "slot/-x", "slot/+y", "slot/-y"]
        assert FIXTURES in sim.collision.group_names()
        # The -y wall's inner face is 0.31 / 2 from the centre: a point just inside it is
        # 5 mm... from the wall: FCL sees the walls where PyBullet has them.
        d, _ = sim.collision.query(np.array([[0.60, -0.18 - 0.155 + 0.005, 0.62]]))
        assert d[0] == pytest.approx(0.005, abs=1e-4) or d[0] > 0.0
