"""The ``trials.hard`` section of a world file: its defaults, what is refused and how."""

from __future__ import annotations

import re
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

import app
from worlds.testing import DEFAULT_WORLD
from worlds.world_file import HardSettings, WorldFileError, load_world

WriteWorld = Callable[[dict[str, Any], str], Path]


def test_the_defaults_are_issue_16s() -> None:
    h = HardSettings()
    assert (h.mass_scale, h.friction_scale, h.palm_friction_scale) == (
        (0.5, 1.5),
        (0.7, 1.3),
        (0.8, 1.2),
    )
    assert (h.table_dz_m, h.pose_sigma_m, h.yaw_sigma_deg) == ((-0.03, 0.03), 0.005, 2.0)
    assert (h.push_rate_hz, h.push_force_n, h.push_duration_s) == (0.2, (5.0, 20.0), (0.05, 0.2))
    assert (h.torque_scale, h.torque_bias, h.torque_lag_s, h.latency_ticks) == (
        (0.85, 1.15),
        0.03,
        (0.01, 0.03),
        1,
    )


def test_default_settings_dump_as_before_and_others_are_kept(
    default_data: dict[str, Any], write_world: WriteWorld
) -> None:
    world = load_world(DEFAULT_WORLD)
    assert "hard" not in world.model_dump(mode="json")["trials"]
    default_data["trials"]["hard"] = {"mass_scale": [0.9, 1.1], "latency_ticks": 0}
    changed = load_world(write_world(default_data, "hard.yaml"))
    assert changed.trials.hard.mass_scale == (0.9, 1.1)
    assert changed.trials.hard.friction_scale == (0.7, 1.3)  # the others keep their defaults
    dumped = changed.model_dump(mode="json")["trials"]["hard"]
    assert (dumped["mass_scale"], dumped["latency_ticks"]) == ([0.9, 1.1], 0)


@pytest.mark.parametrize(
    ("hard", "match"),
    [
        ({"mass_scale": [0.0, 1.0]}, r"trials\.hard\.mass_scale: expected values > 0, got \[0"),
        ({"friction_scale": [-0.1, 1]}, r"trials\.hard\.friction_scale: expected values >= 0"),
        ({"torque_scale": [1.2, 0.8]}, r"trials\.hard\.torque_scale: expected low <= high"),
        ({"push_duration_s": [0, 0.1]}, r"trials\.hard\.push_duration_s: expected values > 0"),
        (
            {"table_dz_m": [-0.08, 0.0]},
            r"trials\.hard\.table_dz_m: expected heights within \[-0\.05, 0\.05\] m \(an "
            r"object more than 5 cm below where the file puts it reads to the robot as fallen",
        ),
        ({"table_dz_m": [0.0, 2.0]}, r"trials\.hard\.table_dz_m: expected heights within"),
        ({"pose_sigma_m": -0.001}, r"trials\.hard\.pose_sigma_m: expected a number greater"),
        ({"push_rate_hz": 50}, r"trials\.hard\.push_rate_hz: expected a number less than or"),
        ({"latency_ticks": 1.5}, r"trials\.hard\.latency_ticks: expected a whole number"),
        ({"torque_bias": "3 %"}, r"trials\.hard\.torque_bias: expected a number, got '3 %'"),
        ({"lag": 0.01}, r"trials\.hard\.lag: expected only the keys mass_scale"),
    ],
)
def test_bad_values_are_refused_naming_file_field_and_expectation(
    default_data: dict[str, Any],
    write_world: WriteWorld,
    hard: dict[str, Any],
    match: str,
    capsys: pytest.CaptureFixture[str],
) -> None:
    default_data["trials"]["hard"] = hard
    path = write_world(default_data, "hard.yaml")
    with pytest.raises(WorldFileError, match=rf"^{re.escape(str(path))}: {match}"):
        load_world(path)
    with pytest.raises(SystemExit) as exited:
        app.main(["trials", str(path), "--hard", "--n", "1"])
    assert exited.value.code == app.EXIT_BAD_INPUT
    assert re.search(match, capsys.readouterr().err)
