"""planner.runner.tick_tree ticks a tree as py_trees' BehaviourTree.tick does."""

from __future__ import annotations

import py_trees
from py_trees.common import Status

from planner.runner import tick_tree


class _Visits(py_trees.visitors.VisitorBase):
    def __init__(self, full: bool) -> None:
        super().__init__(full=full)
        self.seen: list[list[tuple[str, Status]]] = []

    def initialise(self) -> None:
        self.seen.append([])

    def run(self, behaviour: py_trees.behaviour.Behaviour) -> None:
        self.seen[-1].append((behaviour.name, behaviour.status))


def _tree() -> tuple[py_trees.trees.BehaviourTree, _Visits, _Visits, list[int]]:
    root = py_trees.composites.Sequence("root", memory=True)
    root.add_children(
        [
            py_trees.behaviours.StatusQueue(
                "a", [Status.RUNNING, Status.SUCCESS], eventually=Status.SUCCESS
            ),
            py_trees.composites.Selector(
                "pick",
                memory=False,
                children=[
                    py_trees.behaviours.Failure("no"),
                    py_trees.behaviours.StatusQueue(
                        "b", [Status.RUNNING, Status.RUNNING], eventually=Status.SUCCESS
                    ),
                ],
            ),
        ]
    )
    tree = py_trees.trees.BehaviourTree(root)
    partial, full = _Visits(False), _Visits(True)
    tree.visitors += [partial, full]
    handled: list[int] = []
    tree.add_pre_tick_handler(lambda t: handled.append(-t.count))
    tree.add_post_tick_handler(lambda t: handled.append(t.count))
    tree.setup()
    return tree, partial, full, handled


def test_tick_tree_matches_py_trees_tick_per_tick() -> None:
    ours, ours_partial, ours_full, ours_handled = _tree()
    theirs, their_partial, their_full, their_handled = _tree()
    statuses = []
    for _ in range(6):
        tick_tree(ours)
        theirs.tick()
        pairs = [
            (a.name, a.status, b.status)
            for a, b in zip(ours.root.iterate(), theirs.root.iterate(), strict=True)
        ]
        statuses.append([s for _, s, _ in pairs])
        assert all(x == y for _, x, y in pairs)
    assert ours_partial.seen == their_partial.seen
    assert ours_full.seen == their_full.seen
    assert ours_handled == their_handled and ours.count == theirs.count == 6
    # The tree ran its course, through RUNNING to SUCCESS.
    roots = [s[0] for s in statuses]
    assert roots[0] == Status.RUNNING and roots[-1] == Status.SUCCESS


def test_without_a_full_visitor_the_tree_is_not_walked(monkeypatch) -> None:
    tree, partial, full, _ = _tree()
    tree.visitors.remove(full)
    walked: list[str] = []
    original = py_trees.behaviour.Behaviour.iterate

    def iterate(self, direct_descendants=False):  # type: ignore[no-untyped-def]
        walked.append(self.name)
        return original(self, direct_descendants)

    monkeypatch.setattr(py_trees.behaviour.Behaviour, "iterate", iterate)
    tick_tree(tree)
    assert walked == []
    assert [name for name, _ in partial.seen[-1]] == ["a", "root"]  # children yield first
