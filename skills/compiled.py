"""The composition step compiled with numba: an optional path, the same numbers as the float one.

:class:`skills.composer.DualArmComposer` runs its step in Python floats by default. Started
with ``compiled=True`` it packs the move's terms once into flat arrays (a small program of
``[space, kind, offset]`` rows over one block of parameters) and runs each step as one call
into :mod:`skills._kernels`: every space's accelerations, the integration, the phases and the
palms' commands. Results match the float path within 1e-9 (``tests/skills/test_compiled.py``
holds them to it over whole moves).

What runs where:

* Terms with a kernel: the learnt forcing terms (and a forced base model), obstacle steering,
  the potential field and grasp maintenance, each of exactly that class.
* Any other term (limit repulsion, force-tracking grasp, a saturated sum, a user's own)
  keeps its float path, evaluated in Python at the same state before the call; its
  accelerations are added inside. Such terms cost what they cost in the float path.
* The potential field's distance query: a :class:`skills.couplings.SphereObstacles` is
  evaluated inside the kernel. Any other query is the caller's Python callable, and compiled
  code never calls back into Python: the field's world points come out of one small kernel,
  the query runs in Python, and its distances and closest points are written into the
  field's block before the step's call.

It needs numba (``pip install -e '.[fast]'``); :func:`available` says whether it is installed.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from skills import _kernels as k
from skills.composer import DualArmState
from skills.coupling import ScalarTerm, scalar_evaluation
from skills.couplings.grasp import GraspMaintenance
from skills.couplings.potential import DistanceQuery, PotentialFieldAvoidance, SphereObstacles
from skills.couplings.steering import ObstacleSteering
from skills.dmp import DMPParams
from skills.labels import Arm
from skills.pose_dmp import (
    LearntForcing,
    PoseFloats,
    PoseModel,
    PoseState,
    PoseTarget,
    Weighted,
)
from skills.types import Array

#: The size of a step's output (:data:`skills.composer.ROW_SIZE`).
SIZE = k.SIZE


def available() -> bool:
    """Whether numba is installed, so that the step is compiled."""
    return k.COMPILED


def require() -> None:
    """Raise a clear error when numba is not installed.

    Raises
    ------
    RuntimeError
        Naming the extra to install.
    """
    if not k.COMPILED:
        raise RuntimeError(
            "compiled: the compiled composition step needs numba, which is not installed; "
            "install it with pip install -e '.[fast]' (or pass compiled=False)"
        )


@dataclass(frozen=True)
class _Query:
    """A potential field's distance query and where its inputs and outputs live."""

    space: int
    offset: int
    points: int
    query: DistanceQuery


@dataclass(frozen=True)
class _Other:
    """A term without a kernel: its float path, weight, space and target."""

    space: int
    evaluate: ScalarTerm
    weight: float
    target: PoseTarget


def _spaces_row(params: DMPParams, target: PoseTarget, attractor: bool) -> list[float]:
    # kp and kd as attractor_floats computes them, so that the products round the same.
    tau = target.tau
    return [
        1.0 if attractor else 0.0,
        params.alpha * params.beta * (1.0 / (tau * tau)),
        params.alpha / tau,
        *target.goal_position.tolist(),
        *target.goal_orientation.tolist(),
        tau,
        params.alpha_s,  # the palms' phases decay as the object's
    ]


class _Data:
    """The blocks being packed, with each distinct basis table stored once."""

    def __init__(self) -> None:
        self.values: list[float] = []
        self.tables: dict[bytes, int] = {}
        self.basis_size = 0

    def table(self, table: Array) -> int:
        """Where ``table`` (3, K) is stored, storing it the first time."""
        key = table.tobytes()
        if key not in self.tables:
            self.tables[key] = len(self.values)
            self.values += table.ravel().tolist()
            self.basis_size = max(self.basis_size, table.shape[1])
        return self.tables[key]

    def forcing(self, weight: float, table: Array, effective: Array, tau: float) -> list[float]:
        """A forcing block: ``[w, K, tau, table offset, W (K, 7)]``."""
        at = self.table(table)
        return [weight, float(table.shape[1]), tau, float(at), *effective.ravel().tolist()]


def _block(
    term: object, weight: float, target: PoseTarget, data: _Data
) -> tuple[int, list[float]] | None:
    """The term's kind and block, or None when it has no kernel."""
    kind = type(term)
    if kind is LearntForcing:
        assert isinstance(term, LearntForcing)
        own = term.own_target(target)
        table = term.basis.exponent_table
        return k.FORCING, data.forcing(weight, table, own.effective_weights, own.tau)
    if kind is ObstacleSteering:
        assert isinstance(term, ObstacleSteering)
        reach = term.radii + term.object_radius
        obstacles = np.hstack((term.centres, reach[:, None])).ravel().tolist()
        return k.STEERING, [
            weight,
            term.gamma,
            term.beta,
            term.k,
            term.max_angle,
            term.min_speed,
            float(term.centres.shape[0]),
            *obstacles,
        ]
    if kind is PotentialFieldAvoidance:
        assert isinstance(term, PotentialFieldAvoidance)
        n = term.points_object.shape[0]
        head = [weight, term.gain, term.beta, term.influence, term.min_distance, term._inv_rho2]
        points = term.points_object.ravel().tolist()
        if type(term.query) is SphereObstacles:  # queried inside the kernel
            spheres = np.hstack((term.query.centres, term.query.radii[:, None]))
            m = spheres.shape[0]
            return k.POTENTIAL, [*head, float(n), float(m), *points, *spheres.ravel().tolist()]
        # Distances and closest points: written every step from the caller's query.
        return k.POTENTIAL, [*head, float(n), -1.0, *points, *([0.0] * (4 * n))]
    if kind is GraspMaintenance:
        assert isinstance(term, GraspMaintenance)
        return k.GRASP, [
            weight,
            *term._ref,
            term.stiffness,
            float(term.damping or 0.0),
            term.rotational_stiffness,
            float(term.rotational_damping or 0.0),
        ]
    return None


@dataclass(frozen=True, eq=False)
class CompiledStep:
    """One move's terms packed for the compiled step (build with :meth:`of`).

    Attributes
    ----------
    spaces : ndarray, shape (3, 13)
        Per space (object, left, right): attractor flag, gains, goal, ``tau``, ``alpha_s``,
        and the largest basis size.
    program : ndarray, shape (T, 3), int
        Per term with a kernel: ``[space, kind, offset]``.
    data : ndarray
        The terms' blocks; the potential fields' query results are written here each step.
    queries : tuple of _Query
    others : tuple of _Other
        Terms evaluated by their float path.
    """

    spaces: Array
    program: npt.NDArray[np.int64]
    data: Array
    queries: tuple[_Query, ...]
    others: tuple[_Other, ...]

    @staticmethod
    def of(
        base: PoseModel,
        target: PoseTarget,
        absolute: Sequence[Weighted],
        relative: Mapping[Arm, Sequence[Weighted]],
        relative_targets: Mapping[Arm, PoseTarget],
    ) -> CompiledStep:
        """Pack a composition: the object's base model and target, each space's terms."""
        require()
        params = base.params
        forced = bool(np.any(target.effective_weights[:, :6]))
        rows = [_spaces_row(params, target, True)]
        rows += [_spaces_row(params, relative_targets[arm], False) for arm in (Arm.LEFT, Arm.RIGHT)]
        program: list[tuple[int, int, int]] = []
        packed = _Data()
        queries: list[_Query] = []
        others: list[_Other] = []
        if forced:
            table = base.position.forcing.basis.exponent_table
            block = packed.forcing(1.0, table, target.effective_weights, target.tau)
            program.append((0, k.BASE_FORCING, len(packed.values)))
            packed.values += block
        terms = [(0, list(absolute), target)] + [
            (i, list(relative.get(arm, ())), relative_targets[arm])
            for i, arm in enumerate((Arm.LEFT, Arm.RIGHT), start=1)
        ]
        for space, weighted, space_target in terms:
            for w in weighted:
                compiled = _block(w.term, w.weight, space_target, packed)
                if compiled is None:
                    evaluate = scalar_evaluation(w.term)
                    others.append(_Other(space, evaluate, w.weight, space_target))
                    continue
                kind, block = compiled
                at = len(packed.values)
                if kind == k.POTENTIAL and block[7] < 0.0:
                    assert isinstance(w.term, PotentialFieldAvoidance)
                    queries.append(_Query(space, at, int(block[6]), w.term.query))
                program.append((space, kind, at))
                packed.values += block
        for row in rows:
            row.append(float(max(packed.basis_size, 1)))
        return CompiledStep(
            np.array(rows),
            np.array(program, dtype=np.int64).reshape(-1, 3),
            np.array(packed.values + [0.0]),  # never empty
            tuple(queries),
            tuple(others),
        )

    def rollout(
        self,
        current: Sequence[PoseState] | None,
        dt: float,
        steps: int,
        values: Array | None = None,
    ) -> Array:
        """``steps`` steps open loop: row ``i`` (of ``(steps, SIZE)``) is step ``i``'s output.

        One call into compiled code when every term has a kernel and no query runs in Python;
        else one call per step. Arguments as :meth:`__call__`.
        """
        out = np.empty((steps, SIZE))
        if steps == 0:
            return out
        if self.queries or self.others:
            out[0] = self(current, dt, values)
            for i in range(1, steps):
                out[i] = self(None, dt, out[i - 1])
            return out
        x = _read(current, values)
        k.rollout(x, self.spaces, self.program, self.data, _NOTHING, float(dt), out)
        return out

    def __call__(
        self, current: Sequence[PoseState] | None, dt: float, values: Array | None = None
    ) -> Array:
        """The next state and the commands (:data:`SIZE` floats) from the current states.

        Parameters
        ----------
        current : sequence of 3 PoseState, or None
            The object's state and the palms' states in {O}; None when ``values`` holds them.
        dt : float
            Control period, s.
        values : ndarray, optional
            The buffer ``current`` is views of (its 57 values, then its 3 phases), if any:
            saves reading the 18 arrays, and making them when no term needs them.
        """
        x = _read(current, values)
        data = self.data
        for q in self.queries:
            points = k.world_points(x, k.STATE * q.space, data, q.offset)
            _write_query(q, data, *q.query(points))
        extra = np.zeros((3, 6)) if self.others else _NOTHING
        poses: dict[int, PoseFloats] = {}  # each space's state read once
        for other in self.others:
            pose = poses.get(other.space)
            if pose is None:
                if current is None:
                    cut = DualArmState.cut_from(x)
                    current = (cut.object, cut.left, cut.right)
                pose = poses[other.space] = PoseFloats.of(current[other.space])
            a = other.evaluate(pose, other.target)
            if other.weight != 1.0:
                a = tuple(other.weight * v for v in a)  # type: ignore[assignment]
            extra[other.space] += a
        out = np.empty(SIZE)
        k.step(x, self.spaces, self.program, data, extra, float(dt), out)
        return out


#: No accelerations from terms without kernels. Never written, but writable: a read-only
#: array is another type to numba, and would compile every kernel a second time.
_NOTHING = np.zeros((3, 6))


def _read(current: Sequence[PoseState] | None, values: Array | None) -> Array:
    """``values``, else the three states' arrays end to end, then their phases (60 floats)."""
    if values is not None:
        return values
    if current is None:
        raise ValueError("current: expected the three states when values are not given")
    o, left, right = current
    return np.concatenate((*o[:6], *left[:6], *right[:6], (o.phase, left.phase, right.phase)))


def _write_query(q: _Query, data: Array, distances: Array, closest: Array) -> None:
    n = q.points
    at = q.offset + k.POTENTIAL_HEADER + 3 * n
    d = np.asarray(distances, dtype=float)
    c = np.asarray(closest, dtype=float)
    if d.shape != (n,) or c.shape != (n, 3):
        raise ValueError(
            f"query: expected distances ({n},) and closest points ({n}, 3), got "
            f"{d.shape} and {c.shape}"
        )
    data[at : at + n] = d
    data[at + n : at + 4 * n] = c.ravel()
