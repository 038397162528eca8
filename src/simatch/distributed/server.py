"""`Server`: the simulator and the judge of a distributed run; the teams connect over Zenoh.

The server is the embedded `Simulation` (same simulator, judge, coaches, same tick order) on a `ZenohBus`,
with no team nodes of its own. In their place it runs the `LockstepGate` (the barrier that waits for the
teams' commands), a StrategyPub for each team whose robots connect one process per robot, the Gazebo-like
interface for privileged clients, and, in real time, a `Pacer`. Its session is a Zenoh router with
per-team credentials and access control (`fairplay`); every process of the run connects to it.

    server = Server(load_scene("msl_5v5"), seed=0, listen=["tcp/127.0.0.1:7447"])
    server.wait_for_teams()
    server.sim.run(seconds=60)
    server.finish()
    print(server.result())
"""

from __future__ import annotations

import logging
import sys
import time
from collections.abc import Callable, Sequence
from pathlib import Path

import numpy as np

from .. import msgs
from ..bus import topics
from ..bus.zenoh_bus import (
    DEFAULT_ENDPOINT,
    LOW_LATENCY,
    MAX_SAMPLE,
    ZenohBus,
    calm_sending_threads,
    open_session,
    zenoh_config,
)
from ..config.loader import LoadedScene
from ..strategy.node import StrategyPub
from . import credentials, protocol
from .fairplay import FairPlay
from .gate import LockstepGate
from .pacing import Pacer
from .registry import JoinError, Proc, ProcState, Registry
from .world_service import WorldService

log = logging.getLogger(__name__)

#: how much longer than the team timeout a team is waited for while its process, connected, sets up [s]
SETTING_UP_GRACE = 300.0


def _stderr(text: str) -> None:
    print(f"simatch server: {text}", file=sys.stderr, flush=True)


class Server:
    def __init__(
        self,
        scene: LoadedScene,
        seed: int = 0,
        *,
        listen: Sequence[str] = (DEFAULT_ENDPOINT,),
        run: str = "default",
        realtime: bool = False,
        deadline: float = 5.0,
        team_timeout: float = 30.0,
        credentials_dir: str | Path | None = None,
        say: Callable[[str], None] = _stderr,
    ):
        spec = scene.spec
        self.scene = scene
        self.run_name = run
        self.realtime = realtime
        self.team_timeout = team_timeout
        #: processes whose liveliness token is up (proc id -> team): one not yet joined is still setting up
        #: (e.g. compiling its kernels: `warmup`), and the teams' wait goes on for it (`wait_for_teams`)
        self.announced: dict[str, str] = {}
        self.say = say
        self.mode = protocol.REALTIME if realtime else protocol.LOCKSTEP
        #: ticks in a row a process may miss before the server stops waiting for it: in real time a late
        #: answer is normal (it applies at the next tick) and only a silent process should stop being waited for
        self.late_after = 4 if realtime else 1
        teams = {t: spec.teams[t].robot_ids() for t in spec.teams}
        self._check_offer_fits(seed)
        self.bus = self._open_bus(listen, teams, credentials_dir)
        self.registry = Registry(spec)
        self._reports: dict[tuple[str, str, str], tuple[float, int]] = {}  # rate limit of refusal/malformed events
        self.ended = False
        try:
            self._start_simulation(seed, deadline, list(teams))
        except BaseException:
            self.bus.close()
            raise

    def _check_offer_fits(self, seed: int) -> None:
        """The scene offer (the scene with its overrides) must fit in one sample to reach the team processes."""
        offered = len(protocol.dumps(protocol.scene_offer(self.scene, seed, self.run_name, self.mode)))
        if LOW_LATENCY and offered > MAX_SAMPLE:
            raise ValueError(
                f"the scene is too large to offer to the team processes ({offered} bytes with its "
                f"overrides; at most {MAX_SAMPLE})"
            )

    def _open_bus(self, listen: Sequence[str], teams: dict, credentials_dir: str | Path | None) -> ZenohBus:
        """The run's Zenoh router, with every team's credentials and the access control that keeps each team to
        its own topics, and the bus on it that checks every sample."""
        run = self.run_name
        self.credentials_dir = Path(credentials_dir) if credentials_dir else credentials.default_dir(run)
        self.creds = credentials.ensure(self.credentials_dir, [*teams, credentials.ADMIN])
        self.fair = FairPlay(run, self.creds, teams)
        admin = self.creds[credentials.ADMIN]
        conf = zenoh_config(
            "router",
            listen=list(listen),
            user=admin.name,
            password=admin.secret,
            users_file=credentials.users_file(self.credentials_dir, self.creds.values()),
            access_control=self.fair.access_control(),
        )
        session = open_session(conf, what=f"listening on {', '.join(listen)}")
        return ZenohBus(
            session,
            run,
            verifier=self.fair.check,
            entry_verifier=self.fair.check_entry,
            on_refused=self._refused,
            on_malformed=self._malformed,
            wake_on_data=False,
            drop_when_congested=True,
            prepare_on_arrival=not self.realtime,
            max_sample=MAX_SAMPLE if LOW_LATENCY else None,
        )

    def _start_simulation(self, seed: int, deadline: float, teams: list[str]) -> None:
        """The embedded simulation on the bus, with the gate, the world service and (in real time) the pacer on
        its clock; then the server answers the teams: scene offers, joins, bundles, goodbyes, liveliness."""
        from ..simulation import Simulation

        spec = self.scene.spec
        self.sim = Simulation(self.scene, seed=seed, bus=self.bus, run_name=self.run_name, teams="external")
        self.pub_events = self.bus.publisher(topics.EVENTS, msgs.GameEvent)
        self._robot_order = {name: i for i, name in enumerate(spec.robot_names())}
        self._topic_order: dict[str, tuple] = {}  # a robot's topic -> its place (see `_order`)
        clock = self.sim.clock
        self.gate = clock.add(
            LockstepGate(
                spec.control.period,
                deadline,
                self.realtime,
                self.registry.active,
                self._on_ack,
                self._on_missed,
                self._order,
                teams=teams,
                phases=protocol.phases(spec, self.mode),
            )
        )
        self.world_service = clock.add(WorldService(self.sim, self.emit))
        self.pacer = clock.add(Pacer(spec.physics.timestep, slack=0.5)) if self.realtime else None
        self.strategy_pubs: dict[str, StrategyPub] = {}
        # one sample per process and tick each way (see protocol): each team's bundles here, its feeds
        # declared and sent by the gate
        for team in teams:
            self.bus.accept_bundles(protocol.bundle_topic(team))
        self.bus.serve(protocol.SCENE, self._on_scene)
        self.bus.serve(protocol.JOIN, self._on_join)
        self._byes = self.bus.subscribe_raw(protocol.BYES, self._on_bye)
        self.bus.watch_liveliness(protocol.ALIVE, self._on_alive)
        self.bus.declare_token(protocol.SERVER_ALIVE)

    # --- events -------------------------------------------------------------------------------------------
    def emit(self, kind: str, team: str = "", robot: int = 0, value: float = 0.0, detail: str = "") -> None:
        self.pub_events.put(
            msgs.GameEvent(
                stamp=self.sim.time,
                type=kind,
                team=team,
                robot=int(robot),
                x=0.0,
                y=0.0,
                value=float(value),
                limit=0.0,
                detail=detail,
            )
        )

    def _report(self, kind: str, who: str, topic: str, text: str) -> None:
        """At most one event a simulated second per (kind, sender, topic), with the count so far."""
        key = (kind, who, topic)
        last, count = self._reports.get(key, (-np.inf, 0))
        count += 1
        now = self.sim.time
        if now - last >= 1.0:
            self._reports[key] = (now, count)
            self.emit(kind, team=who, value=count, detail=f"{text} ({count} so far)")
            log.warning("%s: %s (%d so far)", kind, text, count)
        else:
            self._reports[key] = (last, count)

    def _refused(self, topic: str, why) -> None:
        self._report("refused", getattr(why, "who", ""), topic, str(why))

    def _malformed(self, topic: str, what: str) -> None:
        self._report("malformed_message", "", topic, f"dropped a sample on {topic}: {what}")

    # --- the protocol ----------------------------------------------------------------------------------------
    def _on_scene(self, query) -> None:
        offer = protocol.scene_offer(self.scene, self.sim.seed, self.run_name, self.mode)
        query.reply(query.key_expr, protocol.dumps(offer))

    def _on_join(self, query) -> None:
        payload = query.payload.to_bytes() if query.payload is not None else b""
        attachment = query.attachment.to_bytes() if query.attachment is not None else None
        try:
            req = protocol.loads(payload, "proc", "team", "robots", "kind")
            who = self.fair.identify(protocol.JOIN, payload, attachment)
            team = str(req["team"])
            if who is None:
                raise JoinError("the join request is not signed with a valid credential")
            if who not in (team, credentials.ADMIN):
                self._report("refused", who, protocol.JOIN, f"{who} tried to join as team {team}")
                raise JoinError(f"the credential of {who} cannot serve robots of team {team}")
            proc = Proc(
                id=str(req["proc"]),
                team=team,
                robots=[int(r) for r in req["robots"]],
                kind="team" if req["kind"] == "team" else "robot",
                strategy_pub=bool(req.get("strategy_pub", False)),
                joined_step=self.sim.simulator.step_index,
                host=str(req.get("host", "")),
            )
            for old in self.registry.join(proc):
                self.gate.forget(old.id)
            proc.phase = protocol.phase_of(self.scene.spec, team, proc.robots, self.mode)
            for rid in proc.robots:  # its perception is taken when its tick opens
                self.sim.set_perception_phase(f"{team}/{rid}", proc.phase)
            self.bus.refresh_matching()  # its subscriptions came before its join
            calm_sending_threads()  # Zenoh starts them with the first link: the feeds leave together
        except (protocol.ProtocolError, JoinError, TypeError, ValueError) as exc:
            query.reply_err(protocol.dumps({"error": str(exc)}))
            return
        if proc.strategy_pub and team in self.strategy_pubs:  # the team now fuses its own picture
            self.sim.clock.remove(self.strategy_pubs.pop(team))
        elif not proc.strategy_pub and not self.registry.team_has_strategy_pub(team):
            self._host_strategy_pub(team)
        query.reply(
            query.key_expr,
            protocol.dumps(
                {
                    "ok": True,
                    "step": self.sim.simulator.step_index,
                    "strategy_pub_on_server": team in self.strategy_pubs,
                    "phase": proc.phase,
                }
            ),
        )
        robots = ",".join(str(r) for r in proc.robots)
        self.emit(
            "process_joined",
            team=team,
            robot=proc.robots[0] if len(proc.robots) == 1 else 0,
            value=len(proc.robots),
            detail=f"{proc.kind} process {proc.id} serves {team}/{robots}",
        )
        self.say(f"{proc.label} joined")

    def _host_strategy_pub(self, team: str) -> None:
        """The team's robots run one per process: their StrategyPub runs here (see docs/distributed.md)."""
        if team in self.strategy_pubs:
            return
        spec = self.scene.spec
        self.strategy_pubs[team] = self.sim.clock.add(
            StrategyPub(team, spec.strategy_pub_period, spec.control.strategy_stale_after)
        )

    def _on_ack(self, msg: dict, team: str, arrival: float, in_step: bool):
        proc = self.registry.procs.get(str(msg["proc"]))
        if proc is None or proc.team != team or proc.state is ProcState.GONE:
            return None
        proc.answered += 1
        if proc.state is ProcState.LATE and in_step:  # back (a stale answer is applied, no more)
            proc.state = ProcState.ACTIVE
            proc.streak = 0
            self.emit("process_back", team=team, detail=f"{proc.label} answers again")
        return proc

    def _on_missed(self, ids: set, now: float) -> None:
        for pid in sorted(ids):
            proc = self.registry.procs.get(pid)
            if proc is None or proc.state is not ProcState.ACTIVE:
                continue
            proc.missed += 1
            proc.streak += 1
            if proc.streak < self.late_after:
                continue
            proc.state = ProcState.LATE
            self.emit(
                "process_late",
                team=proc.team,
                value=self.gate.deadline,
                detail=f"{proc.label} did not answer {proc.streak} tick(s) in time: not waited for "
                f"until it answers again",
            )
            self.say(f"{proc.label} is late: not waiting for it")

    def _gone(self, proc_id: str, kind: str, why: str) -> None:
        proc = self.registry.leave(proc_id)
        if proc is None:
            return
        self.gate.forget(proc_id)
        if self.ended:  # leaving after the end is what the end asks for
            return
        self.emit(kind, team=proc.team, detail=f"{proc.label} {why}")
        self.say(f"{proc.label} {why}")

    def _on_bye(self, topic: str, payload: bytes, attachment, arrival: float) -> None:
        try:
            msg = protocol.loads(payload, "proc")
        except protocol.ProtocolError:
            return
        proc = self.registry.procs.get(str(msg["proc"]))
        if proc is not None and proc.team == protocol.team_of(topic):
            self._gone(proc.id, "process_left", "left")

    def _on_alive(self, topic: str, alive: bool) -> None:
        proc_id = topic.rsplit("/", 1)[-1]
        if alive:
            self.announced[proc_id] = protocol.team_of(topic)
        else:
            self.announced.pop(proc_id, None)
            proc = self.registry.procs.get(proc_id)
            if proc is not None and proc.team == protocol.team_of(topic):
                self._gone(proc_id, "process_lost", "was lost (its connection closed)")

    def _order(self, item: tuple) -> tuple:
        """Received samples in the embedded run's order: by robot (scene order), then as they arrived."""
        topic = item[1]
        known = self._topic_order.get(topic)
        if known is not None:
            return known
        head = topic.split("/", 2)
        if len(head) >= 2:
            i = self._robot_order.get(f"{head[0]}/{head[1]}")
            if i is not None:
                if len(self._topic_order) < 4096:  # the same few dozen topics every tick (bounded all the same)
                    self._topic_order[topic] = (i,)
                return (i,)
        if topic == topics.EVENTS:
            try:
                ev = msgs.decode(msgs.GameEvent, item[2])
                return (self._robot_order.get(f"{ev.team}/{ev.robot}", len(self._robot_order)),)
            except msgs.MessageError:
                pass
        return (len(self._robot_order),)

    # --- running ------------------------------------------------------------------------------------------------
    def setting_up(self) -> set[str]:
        """The teams of processes that are connected (their liveliness token is up) but have not joined."""
        return {team for proc_id, team in self.announced.items() if proc_id not in self.registry.procs}

    def wait_for_teams(self, timeout: float | None = None, poll: float = 0.05) -> dict[str, list[int]]:
        """Serve joins until every robot with a strategy is served, or ``timeout`` seconds (default: the
        team timeout) pass; then say which teams are missing, and play without them. Returns the missing.

        A missing team with a process connected but still setting up (compiling its kernels the first time
        on its machine) is waited for up to `SETTING_UP_GRACE` seconds more: it is coming."""
        timeout = self.team_timeout if timeout is None else timeout
        t0 = time.monotonic()
        next_note = t0
        missing = self.registry.missing()
        while missing:
            now = time.monotonic()
            coming = self.setting_up() & set(missing)
            limit = timeout + SETTING_UP_GRACE if coming else timeout
            if now - t0 >= limit:
                break
            if now >= next_note:
                self.say(
                    "waiting for "
                    + "; ".join(
                        f"{team} (robots {','.join(map(str, ids))}{': setting up' if team in coming else ''})"
                        for team, ids in missing.items()
                    )
                    + f" to connect [{limit - (now - t0):.0f} s left]"
                )
                next_note = now + 5.0
            self.bus.pump(min(poll, max(0.0, limit - (now - t0))))
            missing = self.registry.missing()
        waited = time.monotonic() - t0
        for team, ids in missing.items():
            robots = ",".join(map(str, ids))
            self.emit(
                "team_absent",
                team=team,
                value=len(ids),
                detail=f"robots {robots} of {team} not connected after {waited:.0f} s: playing without them",
            )
            self.say(f"team {team} did not connect (robots {robots}) within {waited:.0f} s: playing without it")
        return missing

    def run(self, seconds: float, progress=None) -> None:
        """Wait for the teams, then run ``seconds`` of simulated time (stopping when the judge ends the run)."""
        self.wait_for_teams()
        self.sim.run(seconds=seconds, progress=progress)

    def finish(self, reason: str = "finished", linger: float = 1.0) -> None:
        """Tell every process the run is over, and give them ``linger`` seconds to leave."""
        if self.ended:
            return
        self.ended = True
        try:
            self.bus.put_raw(protocol.END, protocol.dumps({"reason": reason}))
        except Exception as exc:  # the session may already be closing (interrupted)
            log.debug("could not announce the end: %s", exc)
            return
        deadline = time.monotonic() + linger
        while self.registry.active() and time.monotonic() < deadline:
            self.bus.pump(0.05)

    def result(self) -> dict:
        return self.sim.result()

    def stats(self) -> dict:
        """How the distributed run went: processes, answers (``missed``: ticks not answered in time, see
        `LockstepGate`; ``late``: answers that came after the gate stopped waiting, applied at its next tick),
        and how long the commands took (p50/p99 [ms] of every answer, the late ones too):

        * ``latency``: from the tick opening (perception and game command sent) to the answer arriving: the
          whole round trip, the robots' decisions included; ``tick``: to the last answer of a tick that
          every process answered in time (what the server waits at the barrier; in real time, per physics
          step, for that step's processes);
        * its parts, from the clocks of processes on this machine: ``feed`` until the tick reached the
          process (the bus, and the wait for a core), ``processing`` until its answer was ready (decoding,
          the decisions, encoding), ``transit`` until it arrived here (packing and signing it, the bus)."""
        gate = self.gate
        out = {
            "mode": self.mode,
            "ticks": gate.ticks,
            "processes": len(self.registry.procs),
            "answers": len(gate.latencies),
            "missed": gate.missed,
            "late": gate.late,
        }
        for name, values in (
            ("latency", gate.latencies),
            ("tick", gate.completions),
            ("feed", gate.feeds),
            ("processing", gate.thinking),
            ("transit", gate.transits),
        ):
            out.update(_percentiles(name, values, max_too=name == "latency"))
        out.update({"refused": self.bus.stats.refused, "malformed": self.bus.stats.malformed})
        if self.pacer is not None:
            out.update({f"realtime_{k}": v for k, v in self.pacer.stats().items()})
        return out

    def reset_stats(self) -> None:
        """Start `stats` afresh (e.g. after a warm-up: loading, the first kick-off)."""
        gate = self.gate
        for values in (gate.latencies, gate.completions, gate.feeds, gate.thinking, gate.transits):
            values.clear()
        gate.missed = gate.late = 0
        gate.ticks = 0
        if self.pacer is not None:
            self.pacer.reset_stats()

    def close(self) -> None:
        self.sim.close()
        self.bus.close()

    def __enter__(self) -> Server:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def _percentiles(name: str, seconds: Sequence[float], max_too: bool = False) -> dict:
    """``<name>_p50_ms``, ``<name>_p99_ms`` (and ``<name>_max_ms``) of durations in seconds (None if none)."""
    ms = np.array(seconds) * 1e3
    out = {
        f"{name}_p50_ms": round(float(np.percentile(ms, 50)), 3) if ms.size else None,
        f"{name}_p99_ms": round(float(np.percentile(ms, 99)), 3) if ms.size else None,
    }
    if max_too:
        out[f"{name}_max_ms"] = round(float(ms.max()), 3) if ms.size else None
    return out
