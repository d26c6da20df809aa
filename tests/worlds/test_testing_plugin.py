"""worlds.testing: sim_world and make_sim_world load any world file."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]


@pytest.mark.sim
def test_make_sim_world_opens_any_world_file(
    tmp_path: Path, make_sim_world: Callable[[str | Path], Any]
) -> None:
    text = (ROOT / "worlds" / "parcel_pick_place.yaml").read_text(encoding="utf-8")
    small = tmp_path / "small.yaml"
    small.write_text(
        text.replace("size: [0.20, 0.30, 0.15]}", "size: [0.15, 0.25, 0.10]}").replace(
            "position: [0.55, 0.0, 0.675]", "position: [0.55, 0.0, 0.65]"
        ),
        encoding="utf-8",
    )
    world = make_sim_world(small)
    np.testing.assert_allclose(world.object_extents("parcel"), [0.15, 0.25, 0.10])
    assert world.object_pose("parcel").position[2] == pytest.approx(0.65, abs=2e-3)


@pytest.mark.sim
@pytest.mark.world(str(ROOT / "worlds" / "icub_parcel_pick_place.yaml"))
def test_the_world_marker_chooses_sim_worlds_file(sim_world: Any, sim_world_file: Path) -> None:
    assert sim_world_file.name == "icub_parcel_pick_place.yaml"
    np.testing.assert_allclose(sim_world.object_extents("parcel"), [0.13, 0.14, 0.12])
