"""The Zenoh bus: the bus interface across real Zenoh sessions on loopback (a router, as a server opens, and a
client, as a team opens), its safe defaults, and what it does with samples it cannot use."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
import time

import pytest
import zenoh

from simatch import msgs
from simatch.bus import InProcessBus, LockstepClock
from simatch.bus.zenoh_bus import MAX_SAMPLE, ZenohBus, calm_sending_threads, open_session, zenoh_config
from simatch.strategy.node import StrategyPub

from .cluster import ROOT, free_port


@pytest.fixture
def pair():
    """(server bus, client bus): two sessions joined over TCP on loopback."""
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    server = ZenohBus(open_session(zenoh_config("router", listen=[endpoint])), "unit")
    client = ZenohBus(open_session(zenoh_config("client", connect=[endpoint]), wait=10), "unit", eager=True)
    try:
        yield server, client
    finally:
        client.close()
        server.close()


@pytest.fixture
def low_latency_pair():
    """(server bus, client bus) on Zenoh's low-latency transport, with its sample cap."""
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    server = ZenohBus(
        open_session(zenoh_config("router", listen=[endpoint], low_latency=True)), "unit", max_sample=MAX_SAMPLE
    )
    client = ZenohBus(
        open_session(zenoh_config("client", connect=[endpoint], low_latency=True), wait=10),
        "unit",
        eager=True,
        max_sample=MAX_SAMPLE,
    )
    try:
        yield server, client
    finally:
        client.close()
        server.close()


def pump_until(bus, predicate, timeout: float = 5.0) -> None:
    deadline = time.monotonic() + timeout
    while not predicate():
        assert time.monotonic() < deadline, "nothing arrived"
        bus.pump(0.05)


def test_remote_delivery_is_in_order_in_the_owners_thread_and_local_delivery_is_synchronous(pair):
    server, client = pair
    got = []
    client.subscribe("cyan/*/VelCmd", msgs.VelCmd, lambda m: got.append(("vel", m.tick)))
    client.subscribe("cyan/receive_from_coach", msgs.CoachInfo, lambda m: got.append(("coach", m.match_mode)))
    seen_all = []
    client.subscribe_all("cyan/**", lambda topic, m: seen_all.append((topic, msgs.msgtype_name(m))))
    local = []
    server.subscribe("cyan/2/VelCmd", msgs.VelCmd, lambda m: local.append(m.tick))
    vel = server.publisher("cyan/2/VelCmd", msgs.VelCmd)
    coach = server.publisher("cyan/receive_from_coach", msgs.CoachInfo)
    # both routes must be up before the first put (pub/sub drops what nobody is matched to yet)
    pump_until(server, lambda: vel.active and vel.matching and coach.active and coach.matching)
    for k in range(5):
        vel.put(msgs.new(msgs.VelCmd, tick=k, vx=0.5))
        coach.put(msgs.new(msgs.CoachInfo, match_mode=k))
    assert local == [0, 1, 2, 3, 4]  # at once, in this thread
    time.sleep(0.2)
    assert got == []  # nothing runs in Zenoh's threads: the owner pumps
    pump_until(client, lambda: len(got) == 10)
    assert got == [x for k in range(5) for x in (("vel", k), ("coach", k))]
    assert seen_all[:2] == [
        ("cyan/2/VelCmd", "simatch_msgs/msg/VelCmd"),
        ("cyan/receive_from_coach", "simatch_msgs/msg/CoachInfo"),
    ]
    assert client.stats.delivered == 20 and client.stats.malformed == 0


def test_bad_samples_are_dropped_and_counted_never_raised(pair):
    server, client = pair
    got = []
    client.subscribe("cyan/2/OmniVisionInfo", msgs.OmniVisionInfo, lambda m: got.append(m))

    def fragile(m):
        raise LookupError("robot 2 is missing from its own perception")

    client.subscribe("cyan/3/OmniVisionInfo", msgs.OmniVisionInfo, fragile)
    client.subscribe_all("other/**", lambda topic, m: got.append(m))
    time.sleep(0.3)
    key = server.key
    server.session.put(key("cyan/2/OmniVisionInfo"), b"\x00\x01\x00\x00garbage")  # does not decode
    server.session.put(key("cyan/2/OmniVisionInfo"), msgs.encode(msgs.new(msgs.VelCmd)))  # another type
    server.session.put(key("cyan/3/OmniVisionInfo"), msgs.encode(msgs.new(msgs.OmniVisionInfo)))  # node fails
    server.session.put(key("other/x"), b"no type")  # not a message: left out, not counted
    server.session.put(key("other/y"), b"\x00\x01\x00\x00", encoding=zenoh.Encoding("application/cdr;nope"))
    good = msgs.new(msgs.OmniVisionInfo, tick=7)
    server.session.put(key("cyan/2/OmniVisionInfo"), msgs.encode(good))
    pump_until(client, lambda: len(got) == 1)
    assert got[0].tick == 7
    assert client.stats.malformed == 4
    assert client.stats.malformed_by_topic == {"cyan/2/OmniVisionInfo": 2, "cyan/3/OmniVisionInfo": 1, "other/y": 1}


def test_a_verifier_refuses_samples_before_anybody_sees_them(pair):
    server, client = pair
    refused, got = [], []
    server.verifier = lambda topic, payload, attachment: None if attachment == b"ok" else "not signed"
    server.on_refused = lambda topic, why: refused.append((topic, why))
    server.subscribe("cyan/2/VelCmd", msgs.VelCmd, got.append)
    time.sleep(0.3)
    data = msgs.encode(msgs.new(msgs.VelCmd, vx=1.0))
    client.session.put(client.key("cyan/2/VelCmd"), data)
    client.session.put(client.key("cyan/2/VelCmd"), data, attachment=b"ok")
    pump_until(server, lambda: got)
    assert refused == [("cyan/2/VelCmd", "not signed")] and server.stats.refused == 1 and len(got) == 1


def test_the_same_node_code_runs_on_both_transports(pair):
    """A StrategyPub fed over Zenoh publishes exactly what the same node fed in process publishes."""
    server, client = pair

    def run(bus, feed_bus) -> list:
        clock = LockstepClock(bus, 0.005, seed=0)
        clock.add(StrategyPub("cyan", 0.025, 0.1))
        out = []
        bus.subscribe(
            "cyan/TeamStrategy",
            msgs.TeamStrategy,
            lambda m: out.append([(s.agent_id, s.stamp, s.target_x) for s in m.strategies]),
        )
        pubs = [feed_bus.publisher(f"cyan/{rid}/StrategyInfo", msgs.StrategyInfo) for rid in (1, 2)]
        time.sleep(0.3)
        for step in range(0, 60, 5):
            sent = 0
            for rid, pub in zip((1, 2), pubs):
                if step < 30 or rid == 1:  # robot 2 goes silent: it must drop out
                    pub.put(msgs.new(msgs.StrategyInfo, agent_id=rid, stamp=step * 0.005, target_x=rid + step * 0.1))
                    sent += 1
            if bus is not feed_bus:
                want = bus.stats.delivered + sent
                pump_until(bus, lambda bus=bus, want=want: bus.stats.delivered >= want)
            clock.step_index = step
            clock.step()
        return out

    local_bus = InProcessBus("unit")
    assert run(client, server) == run(local_bus, local_bus)


def test_safe_defaults():
    conf = zenoh_config("client", connect=["tcp/127.0.0.1:1"])

    def get(key):
        return json.loads(conf.get_json(key))

    assert get("scouting/multicast/enabled") is False and get("scouting/gossip/enabled") is False
    assert get("listen/endpoints") == [] and get("connect/endpoints") == ["tcp/127.0.0.1:1"]
    assert get("transport/shared_memory/enabled") is False  # killed processes would leave /dev/shm files
    assert get("transport/unicast/lowlatency") is False  # the ordinary transport unless asked
    low = zenoh_config("client", connect=["tcp/127.0.0.1:1"], low_latency=True)
    assert json.loads(low.get_json("transport/unicast/lowlatency")) is True
    assert json.loads(low.get_json("transport/unicast/qos/enabled")) is False


def test_the_interpreter_exits_even_if_nobody_closes_the_bus():
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    script = textwrap.dedent(f"""
        from simatch import msgs
        from simatch.bus.zenoh_bus import ZenohBus, open_session, zenoh_config
        bus = ZenohBus(open_session(zenoh_config("peer", listen=["{endpoint}"])), "unit")
        bus.subscribe("x/**", msgs.VelCmd, print)
        bus.subscribe_raw("y", lambda *a: None)
        print("open", flush=True)
    """)
    t0 = time.monotonic()
    out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=30, cwd=ROOT)
    assert out.returncode == 0 and "open" in out.stdout, out.stderr
    assert time.monotonic() - t0 < 20


def test_a_batch_leaves_as_one_bundle_and_its_entries_arrive_as_if_alone(pair):
    server, client = pair
    got = []
    server.subscribe("cyan/*/VelCmd", msgs.VelCmd, lambda m: got.append(("vel", m.tick)))
    server.subscribe_raw("cyan/lockstep/ack", lambda topic, payload, att, t: got.append(("ack", payload)))
    server.accept_bundles("cyan/lockstep/bundle", verify=False)
    vel = client.publisher("cyan/2/VelCmd", msgs.VelCmd)
    pump_until(client, lambda: vel.matching)
    client.begin_batch()
    for k in range(3):
        vel.put(msgs.new(msgs.VelCmd, tick=k))
    client.put_raw("cyan/lockstep/ack", b"done")
    before = client.stats.published
    assert client.send_batch("cyan/lockstep/bundle") == 4
    assert client.stats.published == before  # counted when gathered, sent as one sample
    pump_until(server, lambda: len(got) == 4)
    assert got == [("vel", 0), ("vel", 1), ("vel", 2), ("ack", b"done")]
    assert server.stats.delivered == 3 and server.stats.malformed == 0


@pytest.mark.skipif(not hasattr(os, "sched_getscheduler"), reason="Linux scheduling policies")
def test_zenohs_sending_threads_are_made_batch_and_nothing_else(pair):
    """A put wakes Zenoh's sending thread; as SCHED_BATCH it no longer preempts the putting thread."""
    server, client = pair
    pump_until(client, lambda: True)

    def policies() -> dict:
        out = {}
        for tid in os.listdir("/proc/self/task"):
            with open(f"/proc/self/task/{tid}/comm", encoding="utf-8") as f:
                out[int(tid)] = (f.read().strip(), os.sched_getscheduler(int(tid)))
        return out

    assert calm_sending_threads() >= 1
    after = policies()
    senders = [policy for name, policy in after.values() if name.startswith("tx-")]
    assert senders and all(policy == os.SCHED_BATCH for policy in senders)
    assert all(policy != os.SCHED_BATCH for name, policy in after.values() if not name.startswith("tx-"))
    got = []
    server.subscribe("cyan/1/VelCmd", msgs.VelCmd, got.append)
    vel = client.publisher("cyan/1/VelCmd", msgs.VelCmd)
    pump_until(client, lambda: vel.matching)
    vel.put(msgs.new(msgs.VelCmd, vx=1.0))
    pump_until(server, lambda: got)  # samples still leave


def test_a_feed_carries_what_its_topics_publish_once_flushed_and_nothing_arrives_twice(pair):
    server, client = pair
    feed = server.declare_feed("lockstep/feed/cyan", ["cyan/*/OmniVisionInfo", "lockstep/tick"])
    vision = server.publisher("cyan/1/OmniVisionInfo", msgs.OmniVisionInfo)
    other = server.publisher("magenta/1/OmniVisionInfo", msgs.OmniVisionInfo)
    got = []
    client.take_feed("lockstep/feed/cyan", ["cyan/*/OmniVisionInfo", "lockstep/tick"])
    client.subscribe("cyan/1/OmniVisionInfo", msgs.OmniVisionInfo, lambda m: got.append(("vision", m.tick)))
    client.subscribe_raw("lockstep/tick", lambda topic, payload, att, t: got.append(("tick", payload)))
    pump_until(server, lambda: feed.matching)
    assert not vision.matching and vision.active  # nobody subscribes alone: the feed carries it
    assert not other.active
    for k in range(2):
        vision.put(msgs.new(msgs.OmniVisionInfo, tick=k))
    server.put_raw("lockstep/tick", b"t1")
    time.sleep(0.2)
    assert client.pump(0.0) == 0  # nothing left before the flush
    server.flush_feeds()
    pump_until(client, lambda: len(got) == 3)
    time.sleep(0.2)
    client.pump(0.0)
    assert got == [("vision", 0), ("vision", 1), ("tick", b"t1")]
    assert feed.entries == []
    vision.put(msgs.new(msgs.OmniVisionInfo, tick=2))
    server.flush_feeds(only=["lockstep/feed/magenta"])  # another feed's turn: this one keeps gathering
    assert len(feed.entries) == 1
    server.flush_feeds(only=["lockstep/feed/cyan"])
    pump_until(client, lambda: len(got) == 4)
    assert got[-1] == ("vision", 2) and feed.entries == []


def test_samples_over_the_cap_are_not_sent_and_bundles_over_it_are_cut_and_arrive_whole(low_latency_pair):
    """The low-latency transport breaks a link with a larger sample: the bus never sends one."""
    server, client = low_latency_pair
    got = []
    server.subscribe_raw("cyan/lockstep/ack", lambda topic, payload, att, t: got.append(len(payload)))
    server.subscribe_raw("cyan/big", lambda topic, payload, att, t: got.append(("big", len(payload))))
    server.accept_bundles("cyan/lockstep/bundle", verify=False)
    client.put_raw("cyan/big", bytes(MAX_SAMPLE + 1))  # refused here, counted
    assert client.oversize == {"cyan/big": 1}
    client.begin_batch()
    sizes = [MAX_SAMPLE // 3] * 7 + [MAX_SAMPLE * 2, 10]  # ~2.3 samples' worth, one too large
    for n in sizes:
        client.put_raw("cyan/lockstep/ack", bytes(n))
    client.send_batch("cyan/lockstep/bundle")
    assert client.oversize == {"cyan/big": 1, "cyan/lockstep/ack": 1}
    client.put_raw("cyan/big", b"after")  # the link still works
    pump_until(server, lambda: len(got) == 9)
    assert got == [n for n in sizes if n <= MAX_SAMPLE] + [("big", 5)]
    assert server.stats.malformed == 0


def test_a_client_without_the_low_latency_transport_still_plays_with_one_that_has_it():
    """A client in another language (or an older tool) keeps Zenoh's ordinary transport: same samples."""
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    server = ZenohBus(
        open_session(zenoh_config("router", listen=[endpoint], low_latency=True)), "unit", max_sample=MAX_SAMPLE
    )
    client = ZenohBus(
        open_session(zenoh_config("client", connect=[endpoint], low_latency=False), wait=10), "unit", eager=True
    )
    try:
        got = []
        server.subscribe("cyan/2/VelCmd", msgs.VelCmd, lambda m: got.append(m.tick))
        client.subscribe("cyan/2/OmniVisionInfo", msgs.OmniVisionInfo, lambda m: got.append(-m.tick))
        vel = client.publisher("cyan/2/VelCmd", msgs.VelCmd)
        vision = server.publisher("cyan/2/OmniVisionInfo", msgs.OmniVisionInfo)
        pump_until(client, lambda: vel.matching)
        pump_until(server, lambda: vision.matching)
        vel.put(msgs.new(msgs.VelCmd, tick=3))
        vision.put(msgs.new(msgs.OmniVisionInfo, tick=4))
        pump_until(server, lambda: 3 in got)
        pump_until(client, lambda: -4 in got)
    finally:
        client.close()
        server.close()


def test_an_owner_is_woken_only_when_a_sample_says_so(pair):
    """``subscribe_raw(wakes=...)`` decides in Zenoh's thread which samples wake a waiting owner (a lockstep
    server: only the last answer of a tick); the others wait in the queue, in order."""
    server, client = pair
    seen = []
    server.subscribe_raw(
        "cyan/lockstep/ack",
        lambda topic, payload, att, t: seen.append(payload),
        wakes=lambda topic, payload: payload == b"last",
    )
    pub = client.raw_publisher("cyan/lockstep/ack")
    pump_until(client, lambda: pub.matching)
    pub.put(b"first")
    pub.put(b"second")
    assert server.wait(0.5) is False  # queued, but nobody woken
    pub.put(b"last")
    assert server.wait(5.0) is True
    time.sleep(0.05)
    server.pump(0.0)
    assert seen == [b"first", b"second", b"last"]


def test_a_feeds_messages_share_again_the_parts_their_publisher_shared(pair):
    """The simulator gives a team's robots one RobotInfo list; after the wire they hold one list again
    (nubot builds its team's view and picture once per team when they do: see simatch.bus.sharing)."""
    server, client = pair
    covers = ["cyan/*/OmniVisionInfo"]
    feed = server.declare_feed("lockstep/feed/cyan", covers)
    pubs = [server.publisher(f"cyan/{r}/OmniVisionInfo", msgs.OmniVisionInfo) for r in (1, 2, 3)]
    got = {}
    client.take_feed("lockstep/feed/cyan", covers)
    for r in (1, 2, 3):
        client.subscribe(f"cyan/{r}/OmniVisionInfo", msgs.OmniVisionInfo, lambda m, r=r: got.__setitem__(r, m))
    pump_until(server, lambda: feed.matching)
    team = [msgs.new(msgs.RobotInfo, id=r, x=float(r)) for r in (1, 2)]
    pubs[0].put(msgs.new(msgs.OmniVisionInfo, robot_id=1, robots=team))
    pubs[1].put(msgs.new(msgs.OmniVisionInfo, robot_id=2, robots=team))
    pubs[2].put(msgs.new(msgs.OmniVisionInfo, robot_id=3, robots=[msgs.new(msgs.RobotInfo, id=1, x=1.5)]))
    server.flush_feeds()
    pump_until(client, lambda: len(got) == 3)
    assert got[1].robots is got[2].robots and [r.x for r in got[2].robots] == [1.0, 2.0]
    assert got[3].robots is not got[1].robots and got[3].robots[0].x == 1.5
