"""SimTimeout: times out on the simulated clock given to setup, and resets when halted."""

from __future__ import annotations

import time

import py_trees
import pytest
from py_trees.common import Status

from planner.decorators import SimTimeout
from tests.planner.stub_leaves import FakeClock, StubForever

S, F, R, INV = Status.SUCCESS, Status.FAILURE, Status.RUNNING, Status.INVALID


def _timeout_tree(duration: float, clock: FakeClock) -> tuple[SimTimeout, StubForever]:
    child = StubForever(name="forever")
    timeout = SimTimeout(name="limit", child=child, duration=duration)
    py_trees.trees.BehaviourTree(timeout).setup(clock=clock)
    return timeout, child


def test_times_out_on_simulated_time_not_wall_time() -> None:
    clock = FakeClock(dt=0.25)
    timeout, child = _timeout_tree(1.0, clock)
    expected = [(R, R), (R, R), (R, R), (R, R), (F, INV)]  # t = 0, .25, .5, .75, 1.0
    for tick, (want_timeout, want_child) in enumerate(expected):
        timeout.tick_once()
        assert (timeout.status, child.status) == (want_timeout, want_child), f"tick {tick}"
        clock.advance()
    assert child.halts == 1
    assert "timed out after 1.000 s" in timeout.feedback_message


def test_child_that_finishes_in_time_passes_through() -> None:
    clock = FakeClock(dt=0.1)
    child = py_trees.behaviours.StatusQueue(name="queue", queue=[R, R, S], eventually=S)
    timeout = SimTimeout(name="limit", child=child, duration=1.0)
    timeout.setup(clock=clock)
    statuses = []
    for _ in range(3):
        timeout.tick_once()
        statuses.append((timeout.status, child.status))
        clock.advance()
    assert statuses == [(R, R), (R, R), (S, S)]


def test_failure_of_child_is_reflected_before_the_deadline() -> None:
    clock = FakeClock(dt=0.1)
    child = py_trees.behaviours.StatusQueue(name="queue", queue=[R, F], eventually=F)
    timeout = SimTimeout(name="limit", child=child, duration=1.0)
    timeout.setup(clock=clock)
    timeout.tick_once()
    clock.advance()
    timeout.tick_once()
    assert (timeout.status, child.status) == (F, F)


def test_halting_resets_the_timer() -> None:
    clock = FakeClock(dt=0.25)
    timeout, child = _timeout_tree(1.0, clock)
    for _ in range(3):  # t = 0, .25, .5: running, 0.5 s used
        timeout.tick_once()
        clock.advance()
    timeout.stop(INV)  # halted by a higher-priority branch
    assert (timeout.status, child.status) == (INV, INV)
    assert timeout.start_time is None
    clock.now += 100.0  # long pause while halted
    timeout.tick_once()
    assert (timeout.status, child.status) == (R, R)
    assert timeout.elapsed() == pytest.approx(0.0)
    clock.now += 0.75
    timeout.tick_once()
    assert timeout.status == R  # only 0.75 s since re-entry
    clock.now += 0.25
    timeout.tick_once()
    assert (timeout.status, child.status) == (F, INV)


def test_reentry_after_timeout_starts_a_fresh_timer() -> None:
    clock = FakeClock(dt=0.5)
    timeout, _ = _timeout_tree(0.5, clock)
    statuses = []
    for _ in range(4):
        timeout.tick_once()
        statuses.append(timeout.status)
        clock.advance()
    assert statuses == [R, F, R, F]


def test_without_clock_falls_back_to_monotonic_time() -> None:
    timeout = SimTimeout(name="limit", child=StubForever(name="forever"), duration=1e-4)
    timeout.setup()
    assert timeout.clock is time.monotonic
    timeout.tick_once()
    assert timeout.status == R
    time.sleep(0.002)
    timeout.tick_once()
    assert timeout.status == F


def test_bad_arguments_are_explained() -> None:
    with pytest.raises(ValueError, match=r"limit: duration: expected a positive time in s, got 0"):
        SimTimeout(name="limit", child=StubForever(name="f"), duration=0.0)
    timeout = SimTimeout(name="limit", child=StubForever(name="f"), duration=1.0)
    with pytest.raises(TypeError, match=r"clock: expected a callable returning seconds, got float"):
        timeout.setup(clock=3.0)


def test_sim_timeout_is_not_in_the_global_registry() -> None:
    # It is bound to the XML tag Timeout by the loader, not registered under its class name.
    assert "SimTimeout" not in py_trees.ports.get_ports_registry()
