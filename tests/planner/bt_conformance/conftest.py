"""Helpers for the BT.CPP conformance suite: every tree is XML loaded through the loader."""

from __future__ import annotations

import py_trees
from py_trees.common import Status

from planner.loader import load_tree_string
from tests.planner.stub_leaves import FakeClock

S, F, R, INV = Status.SUCCESS, Status.FAILURE, Status.RUNNING, Status.INVALID


class Ticker:
    """A loaded tree, its nodes by short name, and a simulated clock advanced each tick."""

    def __init__(self, body: str, dt: float = 0.1, single: bool = False) -> None:
        if single:
            text = f'<root BTCPP_format="4"><BehaviorTree>{body}</BehaviorTree></root>'
        else:
            text = (
                '<root BTCPP_format="4" main_tree_to_execute="T">'
                f'<BehaviorTree ID="T">{body}</BehaviorTree></root>'
            )
        self.root = load_tree_string(text, "conformance.xml")
        self.clock = FakeClock(dt=dt)
        self.tree = py_trees.trees.BehaviourTree(self.root)
        self.tree.setup(clock=self.clock)
        self.nodes = {n.name.rsplit(".", 1)[-1]: n for n in self.root.iterate()}

    def tick(self, *names: str) -> tuple[Status, ...]:
        """Tick once; return the status of each named node."""
        self.tree.tick()
        self.clock.advance()
        return tuple(self.nodes[n].status for n in names)

    def run(self, names: tuple[str, ...], expected: list[tuple[Status, ...]]) -> None:
        """Tick once per expected row and assert each row."""
        for i, want in enumerate(expected):
            got = self.tick(*names)
            assert got == want, f"tick {i + 1}: {names} = {got}, expected {want}"
