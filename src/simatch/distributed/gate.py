"""The lockstep barrier of a distributed run: the server's stand-in for the robot nodes of the embedded run.

It is the first node of the ROBOT phase. At every control tick (in real time: at every physics step, for
the processes of that step's phase, see `protocol.phase_of`), once the simulator (SENSE), the judge and
coaches (JUDGE) and any StrategyPub the server runs (TEAM) have published, it

1. opens the tick (``lockstep/tick/<phase>``, and the feeds of that phase): each team or robot process
   runs its StrategyPub and RobotNodes for that tick, exactly as the embedded clock would, and answers
   with its commands then an ``ack``;
2. waits for the ack of every active process of the phase, up to a deadline (lockstep), or up to most of
   the time until the next step at which a tick opens (real time: a later command applies at the next
   step, as on a real robot; a tick is missed only if its answer has not come when the process's next
   tick opens);
3. hands the commands, strategy infos and events it received to the simulator and the other nodes, sorted
   into the embedded run's order (robots in scene order, each robot's samples in the order it sent them).

So in lockstep commands of tick k apply before the physics of step k, and a StrategyPub at tick k fuses
what robots sent at tick k-1: the same data flow as embedded, which is why the state digests are equal.
"""

from __future__ import annotations

import json
import threading
import time
from collections.abc import Callable, Sequence

from ..bus import Node, NodeContext, Phase
from . import protocol

#: how many of a process's newest unanswered ticks are kept, to time their answers should they come
OPEN_KEPT = 8


class LockstepGate(Node):
    phase = Phase.ROBOT
    name = "lockstep_gate"

    def __init__(
        self,
        period: float,
        deadline: float,
        realtime: bool,
        active: Callable[[], list],
        on_ack: Callable[[dict, str, float, bool], object],
        on_missed: Callable[[set, float], None],
        order: Callable[[tuple], object],
        teams: Sequence[str] = (),
        phases: int = 1,
    ):
        """``period``: the control period, of ``phases`` phases (1, or one per physics step);
        ``active()`` lists the processes to wait for (objects with ``id`` and ``phase``);
        ``on_ack(msg, team, arrival, in_step)`` returns the process that answered (or None; ``in_step``: a
        late process answering so is waited for again); ``on_missed(ids, now)``
        hears who did not answer in time; ``order(item)`` sorts received samples into the embedded order;
        ``teams``: whose feeds the gate declares and sends."""
        self.control_period = period
        self.period = period / phases
        self.phases = phases
        self.teams = tuple(teams)
        self.deadline = deadline
        self.realtime = realtime
        self._active = active
        self._on_ack = on_ack
        self._on_missed = on_missed
        self._order = order
        # every answer in time [s]; the parts need the process's clock to be this one's (same machine)
        self.latencies: list[float] = []  # tick opened -> answer arrived: the whole round trip
        self.feeds: list[float] = []  # tick opened -> the tick reached the process ("got")
        self.thinking: list[float] = []  # the tick reached the process -> its answer was ready ("sent")
        self.transits: list[float] = []  # the answer was ready -> it arrived here
        #: per tick that every process answered in time: opened -> the last answer arrived [s] (what the
        #: server waits at the barrier)
        self.completions: list[float] = []
        self.ticks = 0
        #: ticks not answered in time: by the deadline (lockstep), or before the process's next tick opened
        #: (real time: an answer after the gate stopped waiting applies at the next physics step, ``late``)
        self.missed = 0
        self.late = 0
        #: per process, the newest ticks it has yet to answer: tick -> [when it opened, counted as missed];
        #: an answer is timed against its tick whenever it comes, so the figures include the late ones
        self._open: dict[str, dict[int, list]] = {}
        self._tick = -1
        self._waiting: set[str] = set()
        self._last_arrival = 0.0
        #: the answers still awaited for tick ``_early_tick`` (process id -> team), as Zenoh's receiving
        #: thread sees them: it wakes the gate only for the last one (see `_last_answer`)
        self._early: dict[str, str] = {}
        self._early_tick = -1
        self._early_lock = threading.Lock()
        #: answers already parsed by Zenoh's thread (`_last_answer`), by payload, for `_ack`
        self._parsed: dict[bytes, dict] = {}

    def start(self, ctx: NodeContext) -> None:
        super().start(ctx)
        self.control_steps = ctx.steps(self.control_period, "control period")
        if self.control_steps % self.phases:
            raise ValueError(f"a control period of {self.control_steps} steps has no {self.phases} phases")
        self.bus = ctx.bus
        self._sub = self.bus.subscribe_raw(protocol.ACKS, self._ack, wakes=self._last_answer)
        #: per phase, each team's feed of that phase (what its processes hear, one sample per tick), and the
        #: tick, which goes into those feeds and alone to processes that take no feed
        every = self.control_steps // self.phases
        self._tick_pubs, self._feeds = {}, {}
        for phase in range(0, self.control_steps, every):
            self._tick_pubs[phase] = self.bus.raw_publisher(protocol.tick_topic(phase), always=False)
            self._feeds[phase] = [
                self.bus.declare_feed(protocol.feed_topic(team, phase), protocol.feed_covers(team, phase)).topic
                for team in self.teams
            ]

    def forget(self, proc_id: str) -> None:
        """Stop waiting for a process (it left or died)."""
        self._waiting.discard(proc_id)
        self._open.pop(proc_id, None)

    def _last_answer(self, topic: str, payload: bytes) -> bool:
        """In Zenoh's thread, as an answer is queued: is it the last one the gate waits for? Only then is
        the gate woken (one wake-up per tick instead of one per process). This only decides when the gate
        looks: the gate itself then checks every answer (`_ack`), and if one was not what it claimed it
        goes back to waiting for the rest."""
        try:
            msg = json.loads(payload)
            proc, tick = msg["proc"], msg["tick"]
        except (ValueError, TypeError, KeyError, UnicodeDecodeError):
            return False
        with self._early_lock:
            if isinstance(msg, dict) and len(self._parsed) < 1024:
                self._parsed[payload] = msg  # read once: `_ack` takes it from here
            if (
                tick != self._early_tick
                or not isinstance(proc, str)
                or self._early.get(proc) != protocol.team_of(topic)
            ):
                return False
            del self._early[proc]
            return not self._early

    def _await(self, procs) -> None:
        """Tell Zenoh's thread which answers of this tick are still awaited."""
        with self._early_lock:
            self._early = {p.id: p.team for p in procs}
            self._early_tick = self._tick

    def _ack(self, topic: str, payload: bytes, attachment, arrival: float) -> None:
        with self._early_lock:
            msg = self._parsed.pop(payload, None)
        if msg is None:
            try:
                msg = protocol.loads(payload, "proc", "tick")
            except protocol.ProtocolError:
                return
        # (a payload parsed by `_last_answer` is the same JSON object, which had "proc" and "tick")
        tick = msg["tick"]
        # in step: in real time, the answer of this control period's tick (a process answering older ones
        # stays late: waiting for it would not bring them sooner); in lockstep, any answer (waiting does)
        proc = self._on_ack(msg, protocol.team_of(topic), arrival, not self.realtime or tick == self._tick)
        opens = self._open.get(proc.id) if proc is not None else None
        if not opens or not isinstance(tick, int):
            return
        entry = opens.pop(tick, None)
        for older in [t for t in opens if t < tick]:
            del opens[older]  # it skipped them (it was behind): they were counted as missed
        if entry is None:
            return
        opened, counted = entry
        if proc.id in self._waiting and tick == self._tick:
            self._waiting.discard(proc.id)
            self._last_arrival = max(self._last_arrival, arrival)
        else:
            self.late += 1
        self.latencies.append(arrival - opened)
        sent, got = msg.get("sent"), msg.get("got")
        if isinstance(sent, float) and 0.0 <= arrival - sent < 60.0:
            self.transits.append(arrival - sent)
            if isinstance(got, float) and opened <= got <= sent:
                self.feeds.append(got - opened)
                self.thinking.append(sent - got)
        if not counted:
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
        self._absorb(bus.take(0.0), pending)  # joins, late answers, requests since the last tick
        self._tick = step // self.control_steps
        phase = step % self.control_steps
        everyone = self._active()
        active = [p for p in everyone if p.phase == phase]
        if self.realtime:  # a process whose last tick is still unanswered, a control period on, missed it
            unanswered = {p.id for p in active if self._count_missed(p.id)}
            if unanswered:
                self.missed += len(unanswered)
                self._on_missed(unanswered, now)
                everyone = self._active()  # one that is now late is not waited for
                active = [p for p in everyone if p.phase == phase]
        self._waiting = {p.id for p in active}
        self._await(active)
        opened = self._last_arrival = time.monotonic()
        for p in active:
            opens = self._open.setdefault(p.id, {})
            opens[self._tick] = [opened, False]
            while len(opens) > OPEN_KEPT:
                del opens[min(opens)]
        self._tick_pubs[phase].put(protocol.dumps({"step": step, "tick": self._tick}))
        bus.flush_feeds(self._feeds[phase])  # each team's inputs of this tick, then the tick
        limit = opened + (
            min(self.deadline, 0.8 * self._until_next(phase, everyone)) if self.realtime else self.deadline
        )
        while self._waiting:
            left = limit - time.monotonic()
            if left <= 0:
                break
            self._absorb(bus.take(left), pending)
            if self._waiting:  # woken by something else, or an answer was refused: look again
                self._await([p for p in active if p.id in self._waiting])
                self._absorb(bus.take(0.0), pending)  # answers queued before that
        with self._early_lock:
            self._early = {}
            self._parsed.clear()  # (an answer handled later is parsed again)
        if self._waiting:
            if not self.realtime:
                for pid in self._waiting:
                    self._count_missed(pid)
                self.missed += len(self._waiting)
                self._on_missed(set(self._waiting), now)
            self._waiting.clear()
        elif active:
            self.completions.append(self._last_arrival - opened)
        pending.sort(key=self._order)
        bus.deliver(pending)
        if phase == 0:
            self.ticks += 1

    def _count_missed(self, proc_id: str) -> bool:
        """Mark the process's unanswered ticks as missed; True if one was not marked yet."""
        fresh = False
        for entry in self._open.get(proc_id, {}).values():
            if not entry[1]:
                entry[1] = fresh = True
        return fresh

    def _until_next(self, phase: int, procs) -> float:
        """Seconds from this step to the next step at which a tick opens for somebody (real time: how long
        the gate may wait here without holding up the next phase)."""
        steps = self.control_steps
        gap = min(((p.phase - phase) % steps or steps for p in procs), default=1)
        return gap * self.period

    def stop(self) -> None:
        self._sub.close()
