"""What is wrong with a tree file: one :class:`TreeProblem` per mistake, and the error that
carries them."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class TreeProblem:
    """One thing wrong with a tree file.

    Attributes
    ----------
    file : str
        The file as given (or the ``source`` label of a string).
    line : int or None
        1-based line of the offending element; None for whole-file problems.
    node : str
        The element as written, e.g. ``<Grasp name="grip">``; empty for whole-file problems.
    message : str
        What is wrong and what was expected.
    column : int or None
        1-based column, for XML syntax errors only.
    """

    file: str
    line: int | None
    node: str
    message: str
    column: int | None = None

    def __str__(self) -> str:
        where = self.file
        if self.line is not None:
            where += f":{self.line}"
            if self.column is not None:
                where += f":{self.column}"
        return f"{where}: {self.node}: {self.message}" if self.node else f"{where}: {self.message}"


class TreeFileError(ValueError):
    """A tree file that cannot be loaded; ``str()`` gives one ``file:line: node: message`` per line.

    Parameters
    ----------
    problems : sequence of TreeProblem
        At least one problem.
    """

    def __init__(self, problems: list[TreeProblem] | tuple[TreeProblem, ...]) -> None:
        if not problems:
            raise ValueError("TreeFileError: expected at least one problem")
        self.problems: tuple[TreeProblem, ...] = tuple(problems)
        super().__init__("\n".join(str(p) for p in self.problems))


class LeafCodeError(RuntimeError):
    """A user's leaf raised other than an impossible value (a bug in its code), or its
    ``update`` returned no status (:mod:`planner.leaves.base`): the message names the file and
    line, the leaf and its class. ``app.py`` reports it as bad input, exit code 2."""


class PortValueError(TypeError):
    """A port's value, read as a node runs, that cannot be converted to the port's type (a
    tree's data, as BT.CPP's ``getInput`` refuses it): the message names the node, the port, the
    value and the type. ``app.py`` reports it as bad input, exit code 2; a
    :class:`planner.leaves.WorldLeaf` fails with it instead (a TypeError)."""
