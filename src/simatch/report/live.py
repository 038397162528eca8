"""The match analysis fed live from a run's bus, for a report (or a tournament's table) without a recording.

`LiveAnalysis` is a SENSE-phase node added after the simulator's: at every control tick it takes the model
states as the simulator just published them (rounded to float32 as the messages are, so the numbers equal
those read back from a recording of the same run), and it listens to ``ball_contacts``, ``events``,
``game_state`` and every robot's ``StrategyInfo``. It only reads: a run with it attached keeps its state
digest.

    with Simulation("msl_5v5", seed=1) as sim:
        live = LiveAnalysis.attach(sim)
        sim.run()
        stats = live.finish(sim.result())
"""

from __future__ import annotations

import numpy as np

from .. import msgs
from ..bus import Node, Phase, topics
from .analysis import MatchAnalysis, MatchMeta

_F32 = np.float32


class LiveAnalysis(Node):
    phase = Phase.SENSE
    name = "report/live-analysis"

    def __init__(self, sim, labels: dict[str, str] | None = None):
        self.sim = sim
        self.period = sim.scene.spec.control.period
        self.analysis = MatchAnalysis(MatchMeta.of_scene(sim.scene, sim.seed, labels))
        self._subs: list = []

    @classmethod
    def attach(cls, sim, labels: dict[str, str] | None = None) -> LiveAnalysis:
        """Add the analysis to ``sim`` (before its first step: what came before is not seen)."""
        return sim.clock.add(cls(sim, labels))

    def start(self, ctx) -> None:
        super().start(ctx)
        bus, a = ctx.bus, self.analysis
        self._subs = [
            bus.subscribe(topics.BALL_CONTACTS, msgs.BallContacts, self._on_contacts),
            bus.subscribe(topics.EVENTS, msgs.GameEvent, a.event),
            bus.subscribe(topics.GAME_STATE, msgs.GameState, a.game_state_message),
            bus.subscribe_all(f"*/*/{topics.STRATEGY_INFO}", self._on_strategy),
        ]

    def _on_contacts(self, m) -> None:
        self.analysis.contacts(m.stamp, m.step, m.touching, m.holder, m.kicker, m.kick_speed, m.lob)

    def _on_strategy(self, topic: str, m) -> None:
        self.analysis.strategy(m.stamp, topic.rsplit("/", 1)[0], m.role)

    def tick(self, now: float) -> None:
        names, pose, twist = self.sim.simulator.model_state_arrays()
        self.analysis.states(self.sim.simulator.step_index, names, pose.astype(_F32), twist.astype(_F32))

    def finish(self, run: dict | None = None) -> dict:
        """The analysis (see `MatchAnalysis.finish`), with the run's result and digest when given."""
        return self.analysis.finish(run_extra(run))

    def stop(self) -> None:
        for sub in self._subs:
            sub.close()
        self._subs = []


def run_extra(run: dict | None) -> dict:
    """What a report keeps of ``sim.result()`` (or a recording's end record) besides the analysis."""
    if not run:
        return {}
    return {
        "result": run.get("result"),
        "state_digest": run.get("state_digest"),
        "sim_seconds": run.get("sim_seconds"),
        "wall_seconds": run.get("wall_seconds"),
    }
