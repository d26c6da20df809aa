"""BT.CPP decorators: KeepRunningUntilFailure, RunOnce, Delay (simulated ms),
RetryUntilSuccessful with num_attempts="-1" and "{key}"."""

from __future__ import annotations

import pytest

from tests.planner.bt_conformance.conftest import INV, F, R, S, Ticker


def leaf(name: str, script: str) -> str:
    return f'<StubScripted name="{name}" script="{script}"/>'


def test_keep_running_until_failure() -> None:
    t = Ticker(
        f'<KeepRunningUntilFailure name="k">{leaf("a", "S,R,S,F")}</KeepRunningUntilFailure>'
    )
    t.run(("k", "a"), [(R, INV), (R, R), (R, INV), (F, F)])
    assert t.nodes["a"].ticks == 4


def test_run_once_then_skip_false_repeats_the_first_result() -> None:
    t = Ticker(f'<RunOnce name="o" then_skip="false">{leaf("a", "R,F,S")}</RunOnce>')
    t.run(("o",), [(R,), (F,), (F,), (F,)])
    assert t.nodes["a"].ticks == 2


def test_run_once_skipped_lets_a_sequence_carry_on() -> None:
    t = Ticker(
        f'<Sequence name="s"><RunOnce name="o">{leaf("a", "S,F")}</RunOnce>{leaf("b", "S")}'
        "</Sequence>"
    )
    t.run(("s", "o"), [(S, S), (S, S)])
    assert t.nodes["a"].ticks == 1


def test_delay_waits_before_ticking_its_child() -> None:
    t = Ticker(f'<Delay name="d" delay_msec="200">{leaf("a", "R,S")}</Delay>', dt=0.1)
    # t = 0, .1: waiting (a not ticked); t = .2: a runs; t = .3: a succeeds.
    t.run(("d", "a"), [(R, INV), (R, INV), (R, R), (S, S)])


def test_delay_restarts_after_a_halt() -> None:
    t = Ticker(
        f'<ReactiveFallback name="f">{leaf("c", "F,S,F")}'
        f'<Delay name="d" delay_msec="100">{leaf("a", "R")}</Delay></ReactiveFallback>',
        dt=0.1,
    )
    t.run(("d", "a"), [(R, INV), (INV, INV), (R, INV), (R, R)])


def test_retry_forever() -> None:
    t = Ticker(
        f'<RetryUntilSuccessful name="r" num_attempts="-1">{leaf("a", "F,F,F,F,F,S")}'
        "</RetryUntilSuccessful>"
    )
    t.run(("r",), [(R,)] * 5 + [(S,)])


def test_retry_attempts_from_the_blackboard() -> None:
    t = Ticker(
        '<Sequence name="s"><SetBlackboard name="w" value="2" output_key="n"/>'
        f'<RetryUntilSuccessful name="r" num_attempts="{{n}}">{leaf("a", "F")}'
        "</RetryUntilSuccessful></Sequence>"
    )
    t.run(("s", "r"), [(R, R), (F, F)])
    assert t.nodes["a"].ticks == 2


def test_a_child_that_lowers_the_attempts_or_cycles_is_heard() -> None:
    # BT.CPP's RetryNode reads num_attempts at every tick and again after each failure, its
    # RepeatNode num_cycles at every tick: a child setting the key changes the count at once.
    t = Ticker(
        '<Sequence name="s"><Script name="init" code="k := 5"/>'
        '<RetryUntilSuccessful name="r" num_attempts="{k}"><Sequence name="try">'
        f'<Script name="lower" code="k := 2"/>{leaf("a", "F")}</Sequence>'
        "</RetryUntilSuccessful></Sequence>"
    )
    t.run(("s", "r"), [(R, R), (F, F)])
    assert t.nodes["a"].ticks == 2
    t2 = Ticker(
        '<Sequence name="s"><Script name="init" code="k := 5"/>'
        '<Repeat name="r" num_cycles="{k}"><Sequence name="once">'
        f'<Script name="lower" code="k := 2"/>{leaf("a", "S")}</Sequence>'
        "</Repeat></Sequence>"
    )
    t2.run(("s", "r"), [(R, R), (S, S)])
    assert t2.nodes["a"].ticks == 2
    # Lowered below the cycles already run, it ends at its next tick, the child unticked
    # (BT.CPP's loop condition is read before the child).
    t3 = Ticker(
        '<Sequence name="s"><Script name="init" code="k := 5"/>'
        '<Repeat name="r" num_cycles="{k}"><Sequence name="once">'
        f'<Script name="lower" code="k := 1"/>{leaf("a", "S")}</Sequence>'
        "</Repeat></Sequence>"
    )
    t3.run(("s", "r"), [(R, R), (S, S)])
    assert t3.nodes["a"].ticks == 1


def test_timeout_msec_from_the_blackboard() -> None:
    t = Ticker(
        '<Sequence name="s"><SetBlackboard name="w" value="200" output_key="ms"/>'
        f'<Timeout name="t" msec="{{ms}}">{leaf("a", "R")}</Timeout></Sequence>',
        dt=0.1,
    )
    t.run(("t", "a"), [(R, R), (R, R), (F, INV)])  # t = 0, .1, .2
    assert t.nodes["a"].halts == 1


def test_repeat_cycles_from_the_blackboard_and_for_ever() -> None:
    t = Ticker(
        '<Sequence name="s"><SetBlackboard name="w" value="3" output_key="n"/>'
        f'<Repeat name="r" num_cycles="{{n}}">{leaf("a", "S")}</Repeat></Sequence>'
    )
    t.run(("r",), [(R,), (R,), (S,)])
    t2 = Ticker(f'<Repeat name="r" num_cycles="-1">{leaf("a", "S,S,S,F")}</Repeat>')
    t2.run(("r",), [(R,), (R,), (R,), (F,)])


@pytest.mark.parametrize(
    ("count", "held"), [('"0"', "0"), ('"{n}"', "0"), ('"-3"', "0"), ('"{n}"', "-2")]
)
def test_zero_or_negative_cycles_or_attempts_tick_nothing(count: str, held: str) -> None:
    # BT.CPP loops while count < n || n == -1: Repeat of 0 cycles (or -2, -3, ...) succeeds
    # and Retry of 0 attempts fails, the child unticked (a literal 0 had repeated for ever, a
    # key holding 0 ticked the child once, and -3 repeated for ever).
    zero = f'<SetBlackboard name="w" value="{held}" output_key="n"/>'
    t = Ticker(
        f'<Sequence name="s">{zero}<Repeat name="r" num_cycles={count}>{leaf("a", "S")}'
        "</Repeat></Sequence>"
    )
    t.run(("s", "r"), [(S, S)])
    assert t.nodes["a"].ticks == 0
    t2 = Ticker(
        f'<Sequence name="s">{zero}<RetryUntilSuccessful name="r" num_attempts={count}>'
        f"{leaf('a', 'S')}</RetryUntilSuccessful></Sequence>"
    )
    t2.run(("s", "r"), [(F, F)])
    assert t2.nodes["a"].ticks == 0
