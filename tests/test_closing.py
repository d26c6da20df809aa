"""duet_robot.closing.Closing: the shared context manager of the logs, worlds and scenes."""

from __future__ import annotations

import pytest

from duet_robot.closing import Closing


class Counted(Closing):
    def __init__(self) -> None:
        self.closed = 0

    def close(self) -> None:
        self.closed += 1


def test_the_block_gets_the_object_and_it_is_closed_after() -> None:
    thing = Counted()
    with thing as got:
        assert got is thing
        assert thing.closed == 0
    assert thing.closed == 1


def test_it_is_closed_when_the_block_raises_and_the_error_goes_on() -> None:
    thing = Counted()
    with pytest.raises(RuntimeError, match="boom"), thing:
        raise RuntimeError("boom")
    assert thing.closed == 1


def test_a_subclass_without_close_says_which() -> None:
    class Bare(Closing):
        pass

    with pytest.raises(NotImplementedError, match=r"Bare\.close"), Bare():
        pass
