"""`TeamProcess`: one team's nodes (``simatch team``), or one robot's (``simatch robot``), in their own process.

It needs no scene file: it asks the server for the scene (text, overrides, seed), builds the very nodes
the embedded run builds (`build_team`: the same RobotNode, WorldModel, strategy and, for a whole team, its
StrategyPub) and ticks them on a `LockstepClock` whose step follows the server's ``lockstep/tick/<phase>``
messages (its phase: `protocol.phase_of`). The nodes talk over a `ZenohBus`, so their code is the embedded code.

A team process may bring its own strategy (``strategy``, ``params``): they override the scene's
``teams.<team>.strategy`` and ``strategy_params`` here only.
"""

from __future__ import annotations

import logging
import os
import socket
import sys
import threading
import time
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

from ..bus import LockstepClock
from ..bus.zenoh_bus import (
    DEFAULT_ENDPOINT,
    LOW_LATENCY,
    MAX_SAMPLE,
    ZenohBus,
)
from ..strategy import NO_NODES
from ..strategy.team import build_team
from . import credentials, protocol
from .connect import ConnectError, open_server_session
from .warmup import preload_compiled_kernels, rehearse

log = logging.getLogger(__name__)


class ClientError(RuntimeError):
    """The process cannot take part in the run (no server, refused join, no strategy...)."""


def _stderr(text: str) -> None:
    print(f"simatch: {text}", file=sys.stderr, flush=True)


class TeamProcess:
    #: it runs the scene's (or its own) strategy for its robots; a bridge whose robots are driven from
    #: outside says False, and has nothing to rehearse before it joins (`warm_up`)
    runs_strategy = True

    def __init__(
        self,
        team: str,
        robots: Sequence[int] | None = None,
        *,
        connect: str = DEFAULT_ENDPOINT,
        run: str = "default",
        key: str | Path | None = None,
        strategy: str | None = None,
        params: Mapping[str, Any] | None = None,
        wait: float = 30.0,
        server_timeout: float = 5.0,
        say: Callable[[str], None] = _stderr,
    ):
        """``robots``: the robot ids to run (None: the whole team, with its StrategyPub); ``wait``: how
        long to wait for the server (and for a robot held by a dead process to be released)."""
        self.team = team
        self.robots = list(robots) if robots is not None else None
        self.kind = "team" if robots is None else "robot"
        self.connect = connect
        self.run_name = run
        self.key = Path(key) if key else credentials.default_dir(run) / f"{team}.key"
        self.strategy = strategy
        self.params = dict(params or {})
        self.wait = wait
        self.server_timeout = server_timeout
        self.say = say
        self.proc = protocol.new_proc_id()
        self.ticks = 0
        self.phase = 0
        self.tick_topic = protocol.tick_topic(0)
        self.skipped = 0  # ticks skipped because a newer one was already there
        self.ended: str | None = None
        self.joined = False
        #: a join is asked and not yet answered: a tick that comes meanwhile is held (`_on_tick`), not dropped
        self._joining = False
        self._held_tick: tuple | None = None
        self._server_alive = False
        self._server_lost_at: float | None = None
        #: the connection to the server came back after it was lost: the server took this process for dead
        #: (``process_lost``), so it joins again before it answers (`serve`)
        self._rejoin = False
        self._serving = False
        self._stop: BaseException | None = None  # asked for by a signal handler (`stop_soon`)
        self.bus: ZenohBus | None = None
        self.stats = None  # the bus's counters (kept after it closes)
        self.clock: LockstepClock | None = None
        #: ticks are answered by Zenoh's receiving thread, the rest by the main thread: one at a time
        self._delivering = threading.Lock()

    @property
    def what(self) -> str:
        return self.team if self.robots is None else ",".join(f"{self.team}/{r}" for r in self.robots)

    # --- setting up ------------------------------------------------------------------------------------------
    def open(self) -> None:
        cred = self._credential()
        if cred.name not in (self.team, credentials.ADMIN):
            raise ClientError(f"{self.key} is the credential of {cred.name}, not of team {self.team}")
        try:
            session = open_server_session(cred, self.connect, self.key, self.wait, say=self.say)
        except ConnectError as exc:
            raise ClientError(str(exc)) from None
        self.bus = ZenohBus(
            session,
            self.run_name,
            signer=cred.signer(self.run_name),
            wake_on_data=False,
            max_sample=MAX_SAMPLE if LOW_LATENCY else None,
        )
        self.stats = self.bus.stats
        try:
            self._setup()
        except BaseException:
            self.close()
            raise

    def _credential(self) -> credentials.Credential:
        """This team's credential; the server writes it when it starts, so wait for it a while."""
        return credentials.await_file(self.key, self.wait)

    def _setup(self) -> None:
        bus = self.bus
        offer = self._ask_scene()
        local: dict[str, Any] = {}
        if self.strategy:
            local[f"teams.{self.team}.strategy"] = self.strategy
        for k, v in self.params.items():
            local[f"teams.{self.team}.strategy_params.{k}"] = v
        scene = protocol.scene_from_offer(offer, local)
        spec = scene.spec
        if self.team not in spec.teams:
            raise ClientError(f"the server's scene has no team {self.team!r} (teams: {', '.join(spec.teams)})")
        self.scene = scene
        self.seed = int(offer["seed"])
        self.mode = offer.get("mode", protocol.LOCKSTEP)
        #: the robots it serves
        self.served = self.robots if self.robots is not None else spec.teams[self.team].robot_ids()
        #: the physics step of each control period at which this process's ticks open (see `protocol`)
        self.phase = protocol.phase_of(spec, self.team, self.served, self.mode)
        self.tick_topic = protocol.tick_topic(self.phase)
        #: one sample per tick each way (the server's feed in, this process's bundle out): see `protocol`
        self.bundles = bool(offer.get("bundles"))
        if self.bundles:  # the tick is answered in the thread that receives it: one hand-off less
            bus.take_feed(
                protocol.feed_topic(self.team, self.phase), protocol.feed_covers(self.team, self.phase), self._answer
            )
        bus.declare_token(protocol.alive_topic(self.team, self.proc))  # the server sees it coming (`warm_up`)
        nodes = self.nodes()
        self.warm_up(offer, local)
        self.clock = LockstepClock(bus, spec.physics.timestep, self.seed, offset=self.phase)
        for node in nodes:
            self.clock.add(node)
        bus.subscribe_raw(self.tick_topic, self._on_tick, verify=False)
        bus.subscribe_raw(protocol.END, self._on_end, verify=False)
        bus.watch_liveliness(protocol.SERVER_ALIVE, self._on_server)
        if self.bundles:  # declared before the join, so that it knows the server listens when ticks come
            bus.raw_publisher(protocol.bundle_topic(self.team))
        self._join()

    def nodes(self) -> list:
        """The nodes this process runs for its robots (a subclass may bring others, e.g. a bridge): the very
        nodes the embedded run builds for them."""
        spec = self.scene.spec
        strategy = str(spec.teams[self.team].strategy)
        if strategy in NO_NODES:
            raise ClientError(
                f"the server's scene does not say which strategy {self.team} plays "
                f"(teams.{self.team}.strategy = {strategy!r}): give --strategy"
            )
        return build_team(
            self.scene, self.team, self.seed, robot_ids=self.robots, with_strategy_pub=self.robots is None
        )

    def warm_up(self, offer: Mapping[str, Any], local: Mapping[str, Any]) -> None:
        """Before joining: load the compiled kernels the strategy's modules have in the disk cache (not at
        the kick-off); if some were never compiled here, rehearse the scene first (`warmup.rehearse`:
        tens of seconds the first time, which no lockstep tick would wait for)."""
        strategy = str(self.scene.spec.teams[self.team].strategy)
        prefixes = ("simatch", strategy.split(":")[0].split(".")[0])
        if not preload_compiled_kernels(prefixes).uncached or not self.runs_strategy or strategy in NO_NODES:
            return
        self.say(f"{self.what}: compiling its strategy's kernels before joining (once per install; up to a minute)")
        t0 = time.monotonic()
        others = {f"teams.{t}.strategy": "none" for t in self.scene.spec.teams if t != self.team}
        rehearse(protocol.scene_from_offer(offer, {**local, **others}), self.team, self.seed)
        self.say(f"{self.what}: compiled in {time.monotonic() - t0:.0f} s")

    def _ask_scene(self) -> dict:
        deadline = time.monotonic() + self.wait
        while True:
            replies = self.bus.query(protocol.SCENE, b"{}", timeout=2.0)
            for ok, payload in replies:
                if ok:
                    return protocol.loads(payload, "scene", "seed")
            if time.monotonic() >= deadline:
                raise ClientError(f"no simatch server for run {self.run_name!r} answers at {self.connect}")
            time.sleep(0.2)

    def _join(self) -> None:
        req = {
            "proc": self.proc,
            "team": self.team,
            "robots": self.served,
            "kind": self.kind,
            "strategy_pub": self.robots is None,
            "host": socket.gethostname(),
            "pid": os.getpid(),
        }
        deadline = time.monotonic() + self.wait
        self._joining = True
        try:
            self._ask_to_join(req, deadline)
        finally:
            self._joining = False
            self._held_tick = None

    def _ask_to_join(self, req: dict, deadline: float) -> None:
        while True:
            why = "no answer"
            for ok, payload in self.bus.query(protocol.JOIN, protocol.dumps(req), timeout=5.0):
                if ok:
                    reply = protocol.loads(payload)
                    if reply.get("phase", self.phase) != self.phase:
                        raise ClientError(
                            f"the server puts {self.what} at phase {reply['phase']}, not "
                            f"{self.phase}: is it another version of simatch?"
                        )
                    # the server's subscriptions (and one it made for this join, e.g. a StrategyPub) were
                    # declared to this session before the answer: from now on, what matches is known
                    self.bus.refresh_matching()
                    with self._delivering:
                        # the server may open its first tick for this process at once: a tick that Zenoh's
                        # thread handed over before this answer was read here is answered now, not lost (the
                        # run would miss that tick and wait for its deadline)
                        self.joined = True
                        held, self._held_tick = self._held_tick, None
                        if held is not None and not self.ended:
                            self._on_tick(*held)
                    where = "; its team's StrategyPub runs on the server" if reply.get("strategy_pub_on_server") else ""
                    at = f", step {self.phase} of each control period" if self.phase else ""
                    self.say(f"{self.what} joined run {self.run_name!r} at {self.connect} ({self.mode}{at}{where})")
                    return
                try:
                    why = protocol.loads(payload, "error")["error"]
                except protocol.ProtocolError:
                    why = payload.decode(errors="replace")
            retry = why == "no answer" or "already served" in why  # a dead predecessor not yet noticed
            if not retry or time.monotonic() >= deadline:
                raise ClientError(f"the server refused {self.what}: {why}")
            time.sleep(0.25)

    # --- the lockstep protocol ---------------------------------------------------------------------------------
    def _on_tick(self, topic: str, payload: bytes, attachment, arrival: float) -> None:
        if not self.joined or self.ended:
            if self._joining and not self.ended:  # the newest tick before the join's answer (see `_join`)
                self._held_tick = (topic, payload, attachment, arrival)
            return
        try:
            msg = protocol.loads(payload, "step", "tick")
            step, tick = int(msg["step"]), int(msg["tick"])
        except (protocol.ProtocolError, TypeError, ValueError) as exc:
            log.warning("ignored a bad tick message: %s", exc)
            return
        clock, bus = self.clock, self.bus
        clock.step_index = step
        if self.bundles:
            bus.begin_batch()
        try:
            clock.step()
            bus.put_raw(protocol.ack_topic(self.team), protocol.ack(self.proc, tick, time.monotonic(), arrival))
        finally:
            if self.bundles:
                bus.send_batch(protocol.bundle_topic(self.team))
        self.ticks += 1

    def _on_end(self, topic: str, payload: bytes, attachment, arrival: float) -> None:
        try:
            self.ended = str(protocol.loads(payload, "reason")["reason"])
        except protocol.ProtocolError:
            self.ended = "ended"

    def _on_server(self, topic: str, alive: bool) -> None:
        if alive and self.joined and self._server_lost_at is not None:
            self.joined = False  # no tick is answered until the server knows this process again
            self._rejoin = True
        self._server_alive = alive
        self._server_lost_at = None if alive else time.monotonic()

    # --- running -------------------------------------------------------------------------------------------------
    def _answer(self) -> None:
        """Deliver what is queued (the nodes run here, one thread at a time)."""
        with self._delivering:
            bus = self.bus
            if bus is not None:  # None once closing: nothing more is answered
                bus.deliver(self._latest_tick_only(bus.take(0.0)))

    def stop_soon(self, exc: BaseException) -> bool:
        """For signal handlers: make `serve` raise ``exc`` between two deliveries (within a quarter of a
        second), never inside a node's step. False when not serving or a stop is already pending: then the
        caller raises it at once."""
        if not self._serving or self._stop is not None:
            return False
        self._stop = exc
        return True

    def serve(self) -> str:
        """Answer the server's ticks until it ends the run (returns its reason); ClientError if it vanishes."""
        bus = self.bus
        self._serving = True
        try:
            while not self.ended:
                bus.wait(0.25)
                self._answer()
                if self._stop is not None:
                    raise self._stop
                self._check_server()
                if self._rejoin and not self.ended:
                    self._rejoin = False
                    self.say(f"{self.what}: the connection to the server came back; joining again")
                    self._join()
            return self.ended
        finally:
            self._serving = False

    def _check_server(self) -> None:
        lost = self._server_lost_at
        if lost is not None and time.monotonic() - lost > self.server_timeout:
            raise ClientError(f"lost the server at {self.connect} (gone for {self.server_timeout:g} s)")

    def _latest_tick_only(self, items: list) -> list:
        """A process that fell behind (it was stopped, or slow) skips the ticks the server has already
        closed: of several queued ticks only the newest is answered (every input is still delivered)."""
        ticks = [n for n, item in enumerate(items) if item[1] == self.tick_topic]
        if len(ticks) < 2:
            return items
        self.skipped += len(ticks) - 1
        stale = set(ticks[:-1])
        return [item for n, item in enumerate(items) if n not in stale]

    def close(self) -> None:
        """Leave (saying so while the server is there to hear it) and close the session."""
        with self._delivering:  # a tick being answered in Zenoh's thread ends first
            bus = self.bus
            if bus is None:
                return
            self.bus = None
        try:
            if self.joined and self._server_alive:
                bus.put_raw(protocol.bye_topic(self.team), protocol.dumps({"proc": self.proc}))
                time.sleep(0.05)  # let the goodbye leave before the session closes
            if self.clock is not None:
                with self._delivering:
                    self.clock.close()
        finally:
            bus.close()  # not under the lock: closing waits for Zenoh's callbacks to return

    def run(self) -> str:
        self.open()
        try:
            return self.serve()
        finally:
            self.close()
