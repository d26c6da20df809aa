"""The insertion's criteria on cases whose answer is known (fake arrays, no physics)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from experiment.insertion import judge_insertion, longest_above, seating_error
from skills import quaternion as quat

DT = 1.0 / 240.0
GOAL = np.array([0.6, -0.17, 0.675])


def _wall_log(force_n: float, seconds: float, wall: int = 2) -> np.ndarray:
    """One second quiet, ``force_n`` on one wall for ``seconds``, one second quiet: (steps, 4)."""
    quiet = np.zeros((240, 4))
    pressed = np.zeros((round(seconds / DT), 4))
    pressed[:, wall] = force_n
    return np.vstack([quiet, pressed, quiet])


def _seat(bottom_mm: float, yaw_deg: float = 0.0) -> tuple[float, float, float]:
    position = GOAL + np.array([0.0, 0.0, bottom_mm / 1000.0])
    q = quat.from_axis_angle(np.array([0.0, 0.0, 1.0]), math.radians(yaw_deg))
    return seating_error(position, q, GOAL, quat.IDENTITY, 0.075, 0.6)


def test_25_n_for_0_4_s_passes_and_for_0_6_s_fails() -> None:
    ok = judge_insertion({"slot": _seat(0.0)}, {"slot": _wall_log(25.0, 0.4)}, DT, {})
    assert ok.ok, ok.reason
    assert ok.figures["slot"]["peak_wall_force_n"] == 25.0
    assert ok.figures["slot"]["longest_above_limit_s"] == pytest.approx(0.4, abs=DT)
    bad = judge_insertion({"slot": _seat(0.0)}, {"slot": _wall_log(25.0, 0.6)}, DT, {})
    assert not bad.ok
    assert "pressed above 20 N for 0.60 s" in bad.reason


def test_the_limit_is_per_wall_and_continuous() -> None:
    # Two walls 0.4 s each, one after the other: neither is pressed 0.5 s at a stretch.
    log = np.vstack([_wall_log(25.0, 0.4, wall=0), _wall_log(25.0, 0.4, wall=1)])
    assert longest_above(log, DT) == pytest.approx(0.4, abs=DT)
    # One wall pressed 0.3 s, let go for a step, 0.3 s again: 0.3 s at a stretch.
    broken = np.concatenate([np.full(72, 30.0), [0.0], np.full(72, 30.0)])
    assert longest_above(broken, DT) == pytest.approx(0.3)
    assert longest_above(np.full(10, 20.0), DT) == 0.0  # at the limit is not above it


def test_seated_within_3_mm_passes_and_4_mm_fails() -> None:
    assert judge_insertion({"slot": _seat(2.0)}, {}, DT, {}).ok
    high = judge_insertion({"slot": _seat(4.0)}, {}, DT, {})
    assert not high.ok and "bottom 4.0 mm above its floor" in high.reason
    assert high.figures["slot"]["seat_bottom_m"] == pytest.approx(0.004)


def test_turned_more_than_3_degrees_fails_but_half_a_turn_fits() -> None:
    assert judge_insertion({"slot": _seat(0.0, yaw_deg=2.0)}, {}, DT, {}).ok
    assert not judge_insertion({"slot": _seat(0.0, yaw_deg=4.0)}, {}, DT, {}).ok
    assert judge_insertion({"slot": _seat(0.0, yaw_deg=180.0)}, {}, DT, {}).ok


def test_a_robot_touching_the_fixture_fails() -> None:
    verdict = judge_insertion({"slot": _seat(0.0)}, {}, DT, {"left_arm ~ slot": 3})
    assert not verdict.ok and verdict.reason == "robot touched a fixture: left_arm ~ slot"
