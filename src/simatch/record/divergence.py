"""Where a re-simulation first departs from its recording: the step and the component.

A recording of format 3 on holds each physics step's component fingerprints (`simatch.sim.components`:
the world's inputs, the drive, ball handling, applied forces, the flight controller, MuJoCo's step, the
ball's bounce, in pipeline order). `ComponentCheck` holds the recorded rows and the re-simulated ones by step
and finds the first step where any differs and, in that step, the first component in pipeline order: the
step before ended with the same state, so that component is where the re-simulation departs.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..sim.components import DESCRIPTIONS


@dataclass
class ComponentDifference:
    """The first step and component whose fingerprint differs (``simulated`` None: not re-simulated)."""

    t: float
    step: int
    component: str
    recorded: int | None  # (None for the run's nodes' messages, compared whole)
    simulated: int | None

    def describe(self) -> str:
        return (
            f"differs from step {self.step} (t={self.t:.3f} s): "
            f"first in {DESCRIPTIONS.get(self.component, self.component)}"
        )


#: what the run's nodes publish that ``--verify strategies`` compares too (by topic leaf), in the order a control
#: tick makes it: perception (SENSE), the referee and coaches (JUDGE), the strategies (TEAM, ROBOT); their
#: commands then enter the world as the step's inputs
DECISIONS = (
    ("perception", ("OmniVisionInfo",)),
    ("referee", ("game_state", "receive_from_coach")),
    ("strategies", ("TeamStrategy", "VelCmd", "ActionCmd", "StrategyInfo")),
)
_GROUP = {leaf: g for g, (_, leaves) in enumerate(DECISIONS) for leaf in leaves}


def decision_of(topic: str) -> int | None:
    """The `DECISIONS` group of a bus topic (None: not one of them)."""
    return _GROUP.get(topic.rsplit("/", 1)[-1])


class DecisionCheck:
    """The messages of the run's nodes (`DECISIONS`), recorded and re-simulated, folded by physics step and
    group into one hash each (the same process hashes both sides, in the order they were published)."""

    def __init__(self):
        self.theirs: dict[tuple[int, int], int] = {}
        self.mine: dict[tuple[int, int], int] = {}

    @staticmethod
    def _fold(into: dict, step: int, topic: str, data: bytes) -> None:
        group = decision_of(topic)
        if group is not None:
            key = (int(step), group)
            into[key] = hash((into.get(key, 0), topic, bytes(data)))

    def recorded(self, topic: str, step: int, data: bytes) -> None:
        self._fold(self.theirs, step, topic, data)

    def simulated(self, topic: str, step: int, data: bytes) -> None:
        self._fold(self.mine, step, topic, data)

    def first(self, upto: int, dt: float) -> ComponentDifference | None:
        """The first step up to ``upto`` and the first group in it whose messages differ."""
        keys = sorted(k for k in set(self.theirs) | set(self.mine) if k[0] <= upto)
        for step, group in keys:
            if self.theirs.get((step, group)) != self.mine.get((step, group)):
                return ComponentDifference(step * dt, step, DECISIONS[group][0], None, None)
        return None


def well_formed(msg, t_ns: int, dt_ns: int) -> bool:
    """Whether a recorded ComponentFingerprints message (None: it did not decode) can be compared: whole rows of
    named components, of steps before the one it was recorded at (a damaged one is left out, not followed)."""
    if msg is None or not len(msg.component) or len(msg.fingerprint) % len(msg.component):
        return False
    return int(msg.step) + len(msg.fingerprint) // len(msg.component) <= t_ns // dt_ns


class ComponentCheck:
    """The component fingerprints recorded and re-simulated, by physics step (see the module)."""

    def __init__(self, dt: float):
        self.dt = dt
        self.theirs: dict[int, tuple[tuple[str, ...], np.ndarray]] = {}
        self.mine: dict[int, tuple[tuple[str, ...], np.ndarray]] = {}
        #: one past the last step whose recorded row was read, and whose re-simulated row was
        self.covered = 0
        self.simulated_to = 0
        self.found: ComponentDifference | None = None

    @staticmethod
    def _rows(step: int, names, flat) -> dict[int, tuple[tuple[str, ...], np.ndarray]]:
        names = tuple(names)
        rows = np.asarray(flat, dtype=np.uint64).reshape(-1, len(names)) if names else np.zeros((0, 0), np.uint64)
        return {int(step) + i: (names, row) for i, row in enumerate(rows)}

    def recorded(self, msg) -> int:
        """Keep a recorded ComponentFingerprints message; the last step it covers (its first if it is empty)."""
        rows = self._rows(msg.step, msg.component, msg.fingerprint)
        self.theirs.update(rows)
        last = max(rows, default=int(msg.step))
        self.covered = max(self.covered, last + 1)
        return last

    def simulated(self, step: int, names, flat) -> None:
        """Keep the re-simulation's rows from physics step ``step`` on."""
        rows = self._rows(step, names, flat)
        self.mine.update(rows)
        self.simulated_to = max(self.simulated_to, max(rows, default=-1) + 1)

    def compare(self, upto: int) -> ComponentDifference | None:
        """Compare the rows of every step up to ``upto`` that is re-simulated by now and forget them; the first
        difference found so far."""
        upto = min(upto, self.simulated_to - 1)
        for step in sorted(k for k in self.theirs if k <= upto):
            names, theirs = self.theirs.pop(step)
            mine = self.mine.pop(step, None)
            if self.found is not None:
                continue
            if mine is None:
                self.found = ComponentDifference(step * self.dt, step, names[0], int(theirs[0]), None)
                continue
            here = dict(zip(mine[0], mine[1].tolist()))
            for name, value in zip(names, theirs.tolist()):
                if here.get(name) != value:
                    self.found = ComponentDifference(step * self.dt, step, name, value, here.get(name))
                    break
        for step in [k for k in self.mine if k <= upto]:
            del self.mine[step]
        return self.found

    def take(self, msg) -> ComponentDifference | None:
        """Keep a recorded message (None: one that did not decode) and compare what is re-simulated by now;
        the first difference found so far."""
        if msg is not None:
            self.compare(self.recorded(msg))
        return self.found

    def settled(self, diff) -> bool:
        """Whether the comparison can stop at the first difference of the states ``diff`` (None: none yet):
        a component differs, or the recorded rows of its step were read (states are published before
        their step's components run: the world as that step took it is compared too)."""
        return diff is not None and (self.found is not None or self.covered > diff.step)
