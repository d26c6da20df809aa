"""A trial of an insertion world: where its fixture stands, and the box it fits.

:func:`place_fixture` rewrites a drawn trial's world data (``trials.insertion``): the named
fixture's centre and yaw drawn from their ranges, the box's size from its range when one is
given (the fixture made for it follows: its inside is always the box's footprint plus the
file's clearance), and every move into that fixture given the seated pose as its goal. A
fixture that would stand on the box's start is drawn again.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from worlds.fixture_schema import InsertionTrials

#: Draws of a fixture's place before the trial is refused.
FIXTURE_DRAWS = 50
#: Least gap between the box at its start and the fixture's outside, m.
START_GAP_M = 0.01


def _footprint_gap(
    centre_a: np.ndarray, half_a: np.ndarray, yaw_a: float, centre_b: np.ndarray, half_b: np.ndarray
) -> float:
    """Gap between two rectangles on the table (a turned, b not), m, by their bounding boxes
    along world x and y (negative: they overlap)."""
    c, s = abs(math.cos(yaw_a)), abs(math.sin(yaw_a))
    reach_a = np.array([c * half_a[0] + s * half_a[1], s * half_a[0] + c * half_a[1]])
    gaps = np.abs(centre_a - centre_b) - reach_a - half_b
    return float(np.max(gaps))


def place_fixture(data: dict[str, Any], rng: np.random.Generator) -> dict[str, Any]:
    """``data`` (a trial world's, as dumped) with its fixture, box and seated goals drawn."""
    settings = InsertionTrials.model_validate(data["trials"]["insertion"])
    fixture = next(f for f in data["fixtures"] if f["name"] == settings.fixture)
    obj = next(o for o in data["objects"] if o["name"] == fixture["for_object"])
    size = np.asarray(obj["shape"]["size"], dtype=float)
    if settings.box_size is not None:
        r = settings.box_size
        size = np.array([rng.uniform(*r.x), rng.uniform(*r.y), rng.uniform(*r.z)])
        obj["shape"]["size"] = size.tolist()
    top = float(data["table"]["position"][2])
    start = np.asarray(obj["pose"]["position"], dtype=float)
    start[2] = top + size[2] / 2.0
    obj["pose"]["position"] = start.tolist()
    start_yaw = math.radians(obj["pose"]["rpy_deg"][2])
    outer_half = (
        size[:2] / 2.0 + fixture.get("clearance", 0.005) + fixture.get("wall_thickness", 0.02)
    )
    for _ in range(FIXTURE_DRAWS):
        centre = np.array([rng.uniform(*settings.x), rng.uniform(*settings.y)])
        yaw = float(rng.uniform(*settings.yaw_deg))
        c, s = abs(math.cos(math.radians(yaw))), abs(math.sin(math.radians(yaw)))
        reach = np.array(
            [c * outer_half[0] + s * outer_half[1], s * outer_half[0] + c * outer_half[1]]
        )
        if _footprint_gap(start[:2], size[:2] / 2.0, start_yaw, centre, reach) >= START_GAP_M:
            break
    else:
        raise RuntimeError(
            f"trials.insertion: no place for {settings.fixture!r} in {FIXTURE_DRAWS} draws "
            f"clear of the box's start by {START_GAP_M} m"
        )
    fixture["position"] = centre.tolist()
    fixture["yaw_deg"] = yaw
    for step in data["task"]:
        if step["object"] != obj["name"]:
            continue
        for move in step["moves"]:
            move["goal"] = {
                "position": [*centre.tolist(), top + size[2] / 2.0],
                "rpy_deg": [0.0, 0.0, yaw],
            }
            move["fixture"] = settings.fixture
    return data


__all__ = ["FIXTURE_DRAWS", "START_GAP_M", "place_fixture"]
