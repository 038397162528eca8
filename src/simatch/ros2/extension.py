"""``simatch run SCENE --ros2``: an embedded run on the ROS 2 graph, watched by a bridge in its own process.

rclpy never runs in the simulation's process. The extension opens a *tap* on the run instead: a Zenoh
endpoint on loopback (a fresh port, the organiser's credential written to a private folder) that offers the
scene as a server does and forwards what an observer needs from the in-process bus — the clock and the game
commands, the game state, the events, and the model states once per control period, in one sample per
control tick (a feed: `simatch.bus.bundle`) — and it starts ``simatch ros2`` as an observer connected to it
(ground truth, /clock, markers, /tf, game state; `simatch.ros2.bridge`). ``set_model_state`` requests from
ROS are applied between two steps.

What the run's process pays: encoding the forwarded messages and one Zenoh put per control tick, once the
bridge listens (`simatch bench --only ros2` measures it). To drive robots from ROS 2, use a server: the ROS
team is a team process there, with the lockstep, the fair play and the watchdog of every team (docs/ros.md).
"""

from __future__ import annotations

import contextlib
import os
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from .. import msgs
from ..bus import Node, NodeContext, Phase, topics
from ..bus.zenoh_bus import ZenohBus, open_session, zenoh_config
from ..distributed import credentials, protocol
from ..errors import UsageError

#: the tap's one sample per control tick: a bundle (`simatch.bus.bundle`) of what it forwards, and the token the
#: bridge declares once it listens (its subscriptions made); both named in the scene offer (``ros2_feed``)
FEED = "ros2/feed"
READY = "ros2/ready"
COVERS = [
    topics.CLOCK,
    topics.GAME_STATE,
    topics.EVENTS,
    topics.MODEL_STATES,
    topics.team_topic("*", topics.RECEIVE_FROM_COACH),
]

#: the shortest wall time between two of the tap's samples [s]: a run faster than real time (lockstep) is
#: sampled for ROS (the newest of each topic, every event) rather than sent whole to a bridge that cannot
#: follow it; in real time every control tick goes
MIN_INTERVAL = 0.02

#: what the tap forwards as it is published (model states: once per control period, by `Tap`)
FORWARDED = {
    topics.CLOCK: msgs.Clock,
    topics.GAME_STATE: msgs.GameState,
    topics.EVENTS: msgs.GameEvent,
}


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class Tap(Node):
    """The embedded run's side of the tap: forwards to Zenoh, and applies requests from it between steps."""

    phase = Phase.JUDGE
    name = "ros2_tap"

    def __init__(self, sim, zbus: ZenohBus, feed, period: float):
        self.sim = sim
        self.zbus = zbus
        self.feed = feed
        self._flushed = -1.0
        self.period = period
        self.applied = 0
        self.refused = 0

    def start(self, ctx: NodeContext) -> None:
        super().start(ctx)
        bus, z = ctx.bus, self.zbus
        self.subs = []
        self.forwarders = {topic: z.publisher(topic, msgtype) for topic, msgtype in FORWARDED.items()}
        for topic, msgtype in FORWARDED.items():
            self.subs.append(bus.subscribe(topic, msgtype, self.forwarders[topic].put))
        self._coach_pubs: dict[str, object] = {}
        self.subs.append(bus.subscribe_all(topics.team_topic("*", topics.RECEIVE_FROM_COACH), self._coach))
        # taken from the simulator at this node's ticks (once per control period), not subscribed to: a
        # subscriber would make the simulator build them at every physics step
        self._models = z.publisher(topics.MODEL_STATES, msgs.ModelStates)
        self.pub_events = bus.publisher(topics.EVENTS, msgs.GameEvent)
        self.world_topic = z.subscribe(topics.SET_MODEL_STATE, msgs.ModelState, self._set_model_state)

    def _coach(self, topic: str, msg) -> None:
        pub = self._coach_pubs.get(topic)
        if pub is None:
            pub = self._coach_pubs[topic] = self.zbus.publisher(topic, msgs.CoachInfo)
        pub.put(msg)

    def _model_states(self, now: float) -> None:
        simulator = self.sim.simulator
        names, pose, twist = simulator.model_state_arrays()
        self._models.put(
            msgs.new(
                msgs.ModelStates,
                stamp=now,
                step=simulator.step_index,
                name=list(names),
                pose=pose.astype(np.float32).ravel(),
                twist=twist.astype(np.float32).ravel(),
            )
        )

    def _set_model_state(self, msg) -> None:
        from ..distributed.world_service import state_of

        try:
            self.sim.set_model_state(msg.name, **state_of(msg))
            self.applied += 1
        except ValueError as exc:  # an unknown model, a bad value: refused as on a server
            self.refused += 1
            self.pub_events.put(
                msgs.new(
                    msgs.GameEvent,
                    stamp=self.sim.time,
                    type="bad_request",
                    detail=f"set_model_state({msg.name!r}): {exc}",
                )
            )

    def tick(self, now: float) -> None:
        self.zbus.pump(0.0)  # requests from ROS, applied here: between two physics steps
        wall = time.perf_counter()
        if wall - self._flushed < MIN_INTERVAL:  # a run faster than real time: ROS gets a sample of it
            return
        self._flushed = wall
        if self._models.active:
            self._model_states(now)
        feed = self.feed
        if len(feed.entries) > len(COVERS):  # after skipped ticks: the newest of each topic, every event
            newest = {topic: (topic, *rest) for topic, *rest in feed.entries if topic != topics.EVENTS}
            events = [e for e in feed.entries if e[0] == topics.EVENTS]
            feed.entries = events + sorted(newest.values(), key=feed.entries.index)
        self.zbus.flush_feeds()  # what was forwarded since the last flush, in one sample

    def stop(self) -> None:
        for sub in getattr(self, "subs", []):
            sub.close()


class Ros2Extension:
    def add_arguments(self, parser) -> None:
        group = parser.add_argument_group("ROS 2")
        group.add_argument(
            "--ros2",
            action="store_true",
            help="put the run on the ROS 2 graph: a 'simatch ros2' observer in its own process publishes "
            "/clock, /tf, markers, model states, game state and commands (needs the ros2 extra; see docs/ros.md)",
        )
        group.add_argument(
            "--ros2-domain-id",
            type=int,
            default=None,
            metavar="N",
            help="the bridge's ROS_DOMAIN_ID (default: the environment's)",
        )
        group.add_argument(
            "--ros2-open-discovery",
            action="store_true",
            help="let the bridge's ROS 2 discovery reach the local network (default: this machine only)",
        )

    def attach(self, sim, args):
        if not getattr(args, "ros2", False):
            return contextlib.nullcontext()
        return attached(sim, domain_id=args.ros2_domain_id, open_discovery=args.ros2_open_discovery)


@contextlib.contextmanager
def attached(sim, *, domain_id: int | None = None, open_discovery: bool = False, wait: float = 60.0, say=None):
    """The tap on ``sim`` and its bridge process, for the ``with`` block; the bridge is told the run ended and
    stopped on the way out (killed if it does not leave within a few seconds)."""
    say = say or (lambda text: print(f"simatch: {text}", file=sys.stderr, flush=True))
    with tempfile.TemporaryDirectory(prefix="simatch-ros2-") as tmp:
        run = f"embedded-{os.getpid()}"
        creds = credentials.ensure(tmp, [credentials.ADMIN])
        admin = creds[credentials.ADMIN]
        endpoint = f"tcp/127.0.0.1:{_free_port()}"
        conf = zenoh_config(
            "router",
            listen=[endpoint],
            user=admin.name,
            password=admin.secret,
            users_file=credentials.users_file(tmp, creds.values()),
        )
        # a bridge that falls behind (a run many times faster than real time) loses samples; it never slows
        # the run down (a blocked put would)
        zbus = ZenohBus(
            open_session(conf, what=f"listening on {endpoint}"),
            run,
            signer=admin.signer(run),
            drop_when_congested=True,
        )
        proc = None
        tap = None
        ready = []
        try:
            offer = protocol.scene_offer(sim.scene, sim.seed, run, protocol.LOCKSTEP)
            offer["ros2_feed"] = {"topic": FEED, "covers": COVERS, "ready": READY}
            offer = protocol.dumps(offer)
            zbus.serve(protocol.SCENE, lambda q: q.reply(q.key_expr, offer))
            zbus.declare_token(protocol.SERVER_ALIVE)
            feed = zbus.declare_feed(FEED, COVERS)
            zbus.watch_liveliness(READY, lambda topic, alive: ready.append(alive))
            tap = sim.clock.add(Tap(sim, zbus, feed, sim.scene.spec.control.period))
            cmd = [sys.executable, "-m", "simatch", "ros2", "--connect", endpoint, "--run", run]
            cmd += ["--key", str(Path(tmp) / f"{credentials.ADMIN}.key"), "--wait", str(wait)]
            if domain_id is not None:
                cmd += ["--domain-id", str(domain_id)]
            if open_discovery:
                cmd += ["--open-discovery"]
            proc = subprocess.Popen(cmd, stdin=subprocess.DEVNULL)
            _wait_for_bridge(zbus, ready, proc, wait, say)
            yield tap
        finally:
            if tap is not None:
                sim.clock.remove(tap)
            _stop_bridge(zbus, proc)
            zbus.close()


def _wait_for_bridge(zbus: ZenohBus, ready: list, proc: subprocess.Popen, wait: float, say) -> None:
    """Until the bridge says it listens (its ``ready`` token: its ROS side is up and it has subscribed to
    everything the tap forwards): the run starts with it watching."""
    deadline = time.monotonic() + wait
    said = False
    while not any(ready):
        zbus.pump(0.05)
        if proc.poll() is not None:
            raise UsageError(f"the ROS 2 bridge exited at start (code {proc.returncode}): see its message above")
        if time.monotonic() > deadline:
            raise UsageError(f"the ROS 2 bridge did not start within {wait:g} s")
        if not said and time.monotonic() > deadline - wait + 2.0:
            say("waiting for the ROS 2 bridge to start...")
            said = True


def _stop_bridge(zbus: ZenohBus, proc: subprocess.Popen | None) -> None:
    """Tell the bridge the run is over; if it does not leave, SIGTERM (it closes its ROS side: no Fast DDS
    file stays in /dev/shm), and only then kill it."""
    if proc is None:
        return
    with contextlib.suppress(Exception):
        zbus.put_raw(protocol.END, protocol.dumps({"reason": "the run is over"}))
    for stop, wait in ((None, 10), (proc.terminate, 5), (proc.kill, 5)):
        if stop is not None:
            stop()
        try:
            proc.wait(wait)
            return
        except subprocess.TimeoutExpired:
            continue
