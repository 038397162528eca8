"""The lockstep barrier of a distributed run: the server's stand-in for the robot nodes of the embedded run.

It is the first node of the ROBOT phase. At every control tick, once the simulator (SENSE), the judge and
coaches (JUDGE) and any StrategyPub the server runs (TEAM) have published, it

1. opens the tick (``lockstep/tick``): each team or robot process runs its StrategyPub and RobotNodes for
   that tick, exactly as the embedded clock would, and answers with its commands then an ``ack``;
2. waits for the ack of every active process, up to a deadline (lockstep), or up to most of a control
   period (real time: a late command applies at the next tick, as on a real robot);
3. hands the commands, strategy infos and events it received to the simulator and the other nodes, sorted
   into the embedded run's order (robots in scene order, each robot's samples in the order it sent them).

So commands of tick k apply before the physics of step k, and a StrategyPub at tick k fuses what robots
sent at tick k-1: the same data flow as embedded, which is why the state digests are equal.
"""

from __future__ import annotations

import time
from typing import Callable

from ..bus import Node, NodeContext, Phase
from . import protocol


class LockstepGate(Node):
    phase = Phase.ROBOT
    name = "lockstep_gate"

    def __init__(self, period: float, deadline: float, realtime: bool, active: Callable[[], list],
                 on_ack: Callable[[dict, str, float], object], on_missed: Callable[[set, float], None],
                 order: Callable[[tuple], object]):
        """``active()`` lists the processes to wait for (objects with ``id``); ``on_ack(msg, team, arrival)``
        returns the process that answered (or None); ``on_missed(ids, now)`` hears who did not answer in
        time; ``order(item)`` sorts received samples into the embedded order."""
        self.period = period
        self.deadline = deadline
        self.realtime = realtime
        self._active = active
        self._on_ack = on_ack
        self._on_missed = on_missed
        self._order = order
        self.latencies: list[float] = []      # tick opened -> ack arrived [s], every answer in time
        self.transits: list[float] = []       # ack sent -> ack arrived [s] (same machine: the same clock)
        self.ticks = 0
        self.missed = 0
        self._tick = -1
        self._opened = 0.0
        self._waiting: set[str] = set()

    def start(self, ctx: NodeContext) -> None:
        super().start(ctx)
        self.control_steps = ctx.steps(self.period, "control period")
        self.bus = ctx.bus
        self._sub = self.bus.subscribe_raw(protocol.ACKS, self._ack)
        #: the tick goes into each team's feed, and alone to processes that take no feed
        self._tick_pub = self.bus.raw_publisher(protocol.TICK, always=False)

    def forget(self, proc_id: str) -> None:
        """Stop waiting for a process (it left or died)."""
        self._waiting.discard(proc_id)

    def _ack(self, topic: str, payload: bytes, attachment, arrival: float) -> None:
        try:
            msg = protocol.loads(payload, "proc", "tick")
        except protocol.ProtocolError:
            return
        proc = self._on_ack(msg, protocol.team_of(topic), arrival)
        if proc is not None and msg["tick"] == self._tick and proc.id in self._waiting:
            self._waiting.discard(proc.id)
            self.latencies.append(arrival - self._opened)
            sent = msg.get("sent")
            if isinstance(sent, float) and 0.0 <= arrival - sent < 60.0:
                self.transits.append(arrival - sent)
            proc.streak = 0

    def _absorb(self, items, pending: list) -> None:
        """Protocol samples (acks, joins, liveliness) are handled at once; data waits to be sorted."""
        bus = self.bus
        for item in items:
            if item[0].raw:
                bus.deliver((item,))
            else:
                pending.append(item)

    def tick(self, now: float) -> None:
        bus = self.bus
        step = self.ctx.step()
        pending: list = []
        self._absorb(bus.take(0.0), pending)          # joins, late answers, requests since the last tick
        self._tick = step // self.control_steps
        self._waiting = {p.id for p in self._active()}
        self._tick_pub.put(protocol.dumps({"step": step, "tick": self._tick}))
        bus.flush_feeds()                              # each team's inputs of this tick, then the tick
        self._opened = opened = time.monotonic()
        limit = opened + (min(self.deadline, 0.8 * self.period) if self.realtime else self.deadline)
        while self._waiting:
            left = limit - time.monotonic()
            if left <= 0:
                break
            self._absorb(bus.take(left), pending)
        if self._waiting:
            self.missed += len(self._waiting)
            self._on_missed(set(self._waiting), now)
            self._waiting.clear()
        pending.sort(key=self._order)
        bus.deliver(pending)
        self.ticks += 1

    def stop(self) -> None:
        self._sub.close()
