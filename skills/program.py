"""How a coupling term packs itself into a composition's program.

A composition (:class:`skills.composer.DualArmComposer`) runs as a small program that one
compiled interpreter (:mod:`skills.interpreter`) executes every step: rows of
``[space, kind, offset]`` over one flat block of parameters. A term that has a kernel packs
its parameters as a block with :meth:`Packer.add` under its :class:`Kind`. A term whose
parameters change while it runs (a distance query answered by FCL, moving link points) also
registers a hook that writes them into its block before each step.

A term without a ``pack`` method still composes: its numpy ``acceleration`` is evaluated
before each step and its result written into an :attr:`Kind.EXTERNAL` block.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from enum import IntEnum
from typing import Protocol, runtime_checkable

from skills.state import STATE_SIZE, PoseTarget, state_from
from skills.types import Array


class Kind(IntEnum):
    """What the interpreter does with a row: which kernel reads its block."""

    FORCING = 0
    BASE_FORCING = 1
    STEERING = 2
    POTENTIAL = 3
    GRASP = 4
    WORKSPACE = 5
    #: Accelerations written by a hook before the step: ``[w, a (6)]``.
    EXTERNAL = 6
    #: Opens a group: the rows until its SATURATE sum on their own.
    GROUP = 7
    #: Closes a group: ``[w, max_linear, max_angular, fade_phase]`` applied to its sum.
    SATURATE = 8


#: ``hook(x, data)``: before a step, write into ``data`` what this step needs, from the state
#: ``x`` the step starts from (the interpreter's layout, :mod:`skills.layout`).
Hook = Callable[[Array, Array], None]


@dataclass
class Packer:
    """The program being packed: rows, one block of parameters, and the hooks.

    Attributes
    ----------
    space : int
        The space the next rows act on: 0 the object, 1 the left palm, 2 the right.
    target : PoseTarget
        The running target of that space.
    """

    space: int
    target: PoseTarget
    rows: list[tuple[int, int, int]] = field(default_factory=list)
    values: list[float] = field(default_factory=list)
    #: Run before every step (open and closed loop).
    hooks: list[Hook] = field(default_factory=list)
    #: Run before a closed-loop step only: what moves in the world but not in a prediction.
    refreshers: list[Hook] = field(default_factory=list)
    tables: dict[bytes, int] = field(default_factory=dict)
    basis_size: int = 0
    #: How many spaces the program has (3 for a dual-arm composition, 1 for a pose DMP): the
    #: phases follow their states.
    spaces: int = 3

    def add(self, kind: Kind, block: list[float]) -> int:
        """Append a row of ``kind`` over ``block`` (its weight first); its offset in the data."""
        at = len(self.values)
        self.rows.append((self.space, int(kind), at))
        self.values += block
        return at

    def term(self, term: object, weight: float) -> None:
        """Pack ``term`` with ``weight``: by its own ``pack``, else as an EXTERNAL block that a
        hook fills with its ``acceleration`` at the step's state."""
        if isinstance(term, Packable):
            term.pack(self, weight)
            return
        acceleration = getattr(term, "acceleration", None)
        if not callable(acceleration):
            raise ValueError(
                f"term: expected a coupling term (an acceleration(state, target) method), "
                f"got {term!r}"
            )
        at = self.add(Kind.EXTERNAL, [weight, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0])
        base, target = STATE_SIZE * self.space, self.target
        phase_at = self.spaces * STATE_SIZE + self.space

        def evaluate(x: Array, data: Array) -> None:
            lin, ang = acceleration(state_from(x, float(x[phase_at]), base), target)
            data[at + 1 : at + 4] = lin
            data[at + 4 : at + 7] = ang

        self.hooks.append(evaluate)

    def table(self, table: Array) -> int:
        """Where the basis exponent table ``table`` (3, K) is stored, storing it once."""
        key = table.tobytes()
        if key not in self.tables:
            self.tables[key] = len(self.values)
            self.values += table.ravel().tolist()
            self.basis_size = max(self.basis_size, int(table.shape[1]))
        return self.tables[key]


@runtime_checkable
class Packable(Protocol):
    """A coupling term with a kernel: it packs itself into a program."""

    def pack(self, packer: Packer, weight: float) -> None:
        """Append this term's rows (weighted by ``weight``) for ``packer.space``."""
        ...
