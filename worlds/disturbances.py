"""Scripted disturbances: forces and torques pushed on objects over windows of simulated time.

The windows come from the world file (:class:`worlds.spec.DisturbanceSpec`, turned into
physics steps by :meth:`~worlds.spec.DisturbanceSpec.steps`). PyBullet clears external forces
after every ``stepSimulation``, so :meth:`Disturbances.apply` is called before every physics
step (by :meth:`worlds.scene.Scene.step`, which every run's stepping goes through) and pushes
each object whose window holds that step, at its centre of mass, in the world frame.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import pybullet as pb

from worlds.spec import DisturbanceSpec


@dataclass(frozen=True)
class AppliedDisturbance:
    """What one disturbance of the world did in a run.

    Attributes
    ----------
    index : int
        Its place in the world file's ``disturbances`` list.
    spec : DisturbanceSpec
        The disturbance.
    first_step : int or None
        The first physics step it acted on (counted from 0 at the start), None if none.
    steps : int
        How many physics steps it acted on (consecutive from ``first_step``).
    skipped : bool
        A ``while_held`` push whose object was not held when its window opened.
    """

    index: int
    spec: DisturbanceSpec
    first_step: int | None
    steps: int
    skipped: bool = False

    @property
    def last_step(self) -> int | None:
        """The last physics step it acted on, None if none."""
        return None if self.first_step is None else self.first_step + self.steps - 1

    def summary(self) -> dict[str, Any]:
        """JSON-ready: the entry as the file gives it, and the physics steps it acted on."""
        d = self.spec
        return {
            "index": self.index,
            "object": d.object,
            "at_s": d.at_s,
            "duration_s": d.duration_s,
            "force_n": list(d.force_n),
            "torque_nm": list(d.torque_nm),
            "first_step": self.first_step,
            "last_step": self.last_step,
            "steps": self.steps,
            **({"while_held": True, "skipped": self.skipped} if d.while_held else {}),
        }


@dataclass(frozen=True)
class _Push:
    """One disturbance ready to apply: its steps, body and PyBullet arguments."""

    first: int
    stop: int
    body: int
    force: list[float]
    torque: list[float] | None
    name: str
    while_held: bool


class Disturbances:
    """The scripted disturbances of one PyBullet scene, applied step by step.

    Parameters
    ----------
    client : int
        PyBullet client.
    specs : sequence of DisturbanceSpec
        The world's disturbances, in file order.
    object_ids : mapping of str to int
        Body id of each object, by name.
    physics_hz : int
        Physics rate, Hz.
    held : callable (name) -> bool, optional
        Whether both palms carry the named object now (hold it off its support,
        :meth:`worlds.scene.Scene.is_carried`); asked once, when a ``while_held``
        push's window opens (without it, such a push is never applied).

    Raises
    ------
    ValueError
        If a disturbance names no object of ``object_ids``.
    """

    def __init__(
        self,
        client: int,
        specs: Sequence[DisturbanceSpec],
        object_ids: Mapping[str, int],
        physics_hz: int,
        held: Callable[[str], bool] | None = None,
    ) -> None:
        unknown = [d.object for d in specs if d.object not in object_ids]
        if unknown:
            raise ValueError(
                f"Disturbances: expected object names in {sorted(object_ids)}, got {unknown}"
            )
        self.client = client
        self.specs = tuple(specs)
        self._pushes: list[_Push] = []
        for d in self.specs:
            window = d.steps(physics_hz)
            self._pushes.append(
                _Push(
                    window.start,
                    window.stop,
                    object_ids[d.object],
                    list(d.force_n),
                    list(d.torque_nm) if any(d.torque_nm) else None,
                    d.object,
                    d.while_held,
                )
            )
        self._held = held
        #: After this step no window holds any step.
        self._end = max((p.stop for p in self._pushes), default=0)
        self._first: list[int | None] = [None] * len(self._pushes)
        self._count = [0] * len(self._pushes)
        self._skipped = [False] * len(self._pushes)

    def __bool__(self) -> bool:
        """Whether there is any disturbance at all (the scene skips :meth:`apply` if not)."""
        return bool(self._pushes)

    def apply(self, step: int) -> None:
        """Push every object whose window holds physics step ``step``; call it before that
        step's ``stepSimulation``.

        Parameters
        ----------
        step : int
            Index of the physics step about to run, counted from 0 at the scene's start.
        """
        if step >= self._end:
            return
        c = self.client
        for i, push in enumerate(self._pushes):
            if not push.first <= step < push.stop or self._skipped[i]:
                continue
            if push.while_held and step == push.first:
                self._skipped[i] = self._held is None or not self._held(push.name)
                if self._skipped[i]:
                    continue
            com, _ = pb.getBasePositionAndOrientation(push.body, physicsClientId=c)
            pb.applyExternalForce(push.body, -1, push.force, com, pb.WORLD_FRAME, physicsClientId=c)
            if push.torque is not None:
                pb.applyExternalTorque(
                    push.body, -1, push.torque, pb.WORLD_FRAME, physicsClientId=c
                )
            if self._first[i] is None:
                self._first[i] = step
            self._count[i] += 1

    def applied(self) -> tuple[AppliedDisturbance, ...]:
        """What each disturbance did so far, in file order."""
        return tuple(
            AppliedDisturbance(i, spec, self._first[i], self._count[i], self._skipped[i])
            for i, spec in enumerate(self.specs)
        )


__all__ = ["AppliedDisturbance", "Disturbances"]
