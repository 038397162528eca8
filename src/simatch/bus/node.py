"""Nodes and the lockstep clock that ticks them.

A node is a participant of a run: it declares its publishers and subscriptions in ``start`` and does its
periodic work in ``tick``. Within each physics step nodes tick in a fixed order of phases, so that every
node handles tick k before the world steps past it:

    SENSE  the simulator publishes the clock, model states and, on control ticks, each robot's perception
    JUDGE  the scene subsystem (referee, coach, judges) reads the world and publishes game commands
    TEAM   each team's StrategyPub publishes the fused team picture
    ROBOT  each robot's WorldModel + Control decide and publish their commands
    ACT    the simulator applies the commands and advances the physics by one step

Within a phase, nodes tick in the order they were added. A transport that spreads nodes over processes
keeps this order by waiting, at each control tick, for the remote nodes' answers (lockstep).
"""

from __future__ import annotations

import enum
import hashlib
import math
from collections.abc import Callable
from dataclasses import dataclass
from functools import partial
from operator import attrgetter

import numpy as np

from .base import Bus


class Phase(enum.IntEnum):
    SENSE = 0
    JUDGE = 10
    TEAM = 20
    ROBOT = 30
    ACT = 40


def stable_seed(seed: int, *names: str) -> list[int]:
    """Entropy for an RNG that depends only on the run seed and a node's name (not on process layout)."""
    digest = hashlib.sha256("/".join(names).encode()).digest()
    return [int(seed) & 0xFFFFFFFF, int.from_bytes(digest[:8], "little")]


@dataclass
class NodeContext:
    """What a node gets from the run it joins."""

    bus: Bus
    dt: float  # physics step [s]
    seed: int
    now: Callable[[], float]  # simulated time [s]
    step: Callable[[], int]  # physics step index

    def rng(self, *names: str) -> np.random.Generator:
        """A random generator private to this node, reproducible for the same seed and name."""
        return np.random.default_rng(stable_seed(self.seed, *names))

    def steps(self, seconds: float, what: str = "period") -> int:
        """A duration as a whole number of physics steps (at least one)."""
        n = round(seconds / self.dt)
        if n < 1 or abs(n * self.dt - seconds) > 1e-9 * max(1.0, seconds):
            raise ValueError(f"{what} {seconds} s is not a whole number of physics steps of {self.dt} s")
        return n


class Node:
    """Base class of every node. Subclasses set ``phase`` and ``period`` (seconds; None = never ticks)."""

    phase: Phase = Phase.ROBOT
    period: float | None = None
    name: str = "node"

    ctx: NodeContext

    def start(self, ctx: NodeContext) -> None:
        """Declare publishers and subscriptions. Called once before the first tick."""
        self.ctx = ctx

    def tick(self, now: float) -> None:
        """Periodic work; ``now`` is the simulated time [s]."""

    def stop(self) -> None:
        """Release what ``start`` took."""


_step_index = attrgetter("step_index")


class LockstepClock:
    """Ticks nodes in phase order, one physics step at a time, in a single thread (the embedded run)."""

    def __init__(self, bus: Bus, dt: float, seed: int, offset: int = 0):
        """``offset``: the step the nodes' periods count from (a node of period p ticks at the steps k with
        (k - offset) % p == 0): a process of a later phase of a real-time run (see `simatch.distributed`)."""
        self.bus = bus
        self.dt = dt
        self.seed = seed
        self.offset = offset
        self.step_index = 0
        self._nodes: list[Node] = []
        self._schedule: list[tuple[Node, int]] = []  # (node, period in steps), sorted by phase
        self._table: list[list] = [[]]  # tick methods due at step k: _table[k % len(_table)]
        self._held: list | None = None  # the rest of a step held by `step_until`
        # (``step`` called from C, without a Python frame: the referee reads it at every physics step)
        self.context = NodeContext(bus=bus, dt=dt, seed=seed, now=self.now, step=partial(_step_index, self))

    def now(self) -> float:
        return self.step_index * self.dt

    @property
    def nodes(self) -> list[Node]:
        return list(self._nodes)

    def add(self, node: Node) -> Node:
        node.start(self.context)
        self._nodes.append(node)
        if node.period is not None:
            period = self.context.steps(node.period, f"period of {node.name}")
            self._schedule.append((node, period))
            self._schedule.sort(key=lambda item: item[0].phase)  # stable: keeps insertion order in a phase
            self._rebuild()
        return node

    def _rebuild(self) -> None:
        """Precompute, for each step of the hyperperiod, the tick methods due at it, in phase order."""
        length = 1
        for _, period in self._schedule:
            length = math.lcm(length, period)
        if length > 10_000:  # periods without a small common multiple: check them one by one
            self._table = []
            return
        self._table = [[node.tick for node, period in self._schedule if k % period == 0] for k in range(length)]

    def remove(self, node: Node) -> None:
        if node in self._nodes:
            self._nodes.remove(node)
            self._schedule = [(n, p) for n, p in self._schedule if n is not node]
            self._rebuild()
            node.stop()

    def _due(self, k: int) -> list[tuple[Phase, Callable[[float], None]]]:
        """(phase, tick) of the nodes due at step ``k``, in tick order."""
        due = k - self.offset
        return [(node.phase, node.tick) for node, period in self._schedule if due % period == 0]

    def step_until(self, phase: Phase) -> None:
        """Tick the current step's nodes of the phases before ``phase`` and hold the step there; the next
        `step` ticks the rest. A learning environment holds each control tick before the ROBOT phase: the
        perception and the game command of the tick are out, and the learner's decision is still to come."""
        if self._held is not None:
            raise RuntimeError("a step is already held: finish it with step() first")
        now = self.step_index * self.dt
        due = self._due(self.step_index)
        i = 0
        while i < len(due) and due[i][0] < phase:
            due[i][1](now)
            i += 1
        self._held = [tick for _, tick in due[i:]]

    @property
    def holding(self) -> bool:
        """A step is held part-way (`step_until`)."""
        return self._held is not None

    def step(self) -> None:
        k = self.step_index
        now = k * self.dt
        if self._held is not None:  # finish the step `step_until` held
            rest, self._held = self._held, None
            for tick in rest:
                tick(now)
            self.step_index = k + 1
            return
        due = k - self.offset
        table = self._table
        if table:
            for tick in table[due % len(table)]:
                tick(now)
        else:
            for node, period in self._schedule:
                if due % period == 0:
                    node.tick(now)
        self.step_index = k + 1

    def close(self) -> None:
        for node in reversed(self._nodes):
            node.stop()
        self._nodes.clear()
        self._schedule.clear()
        self._table = [[]]
