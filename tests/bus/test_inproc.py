"""The in-process bus: synchronous delivery in subscription order, key-expression wildcards, type checks."""

from __future__ import annotations

import numpy as np
import pytest

from simatch import msgs
from simatch.bus import InProcessBus, topics


def test_delivery_order_wildcards_and_late_subscribers():
    bus = InProcessBus("t")
    seen = []
    bus.subscribe("cyan/*/VelCmd", msgs.VelCmd, lambda m: seen.append(("a", m.vx)))
    pub = bus.publisher("cyan/2/VelCmd", msgs.VelCmd)
    bus.subscribe("cyan/2/VelCmd", msgs.VelCmd, lambda m: seen.append(("b", m.vx)))
    bus.subscribe_all("**", lambda topic, m: seen.append(("all", topic)))
    pub.put(msgs.new(msgs.VelCmd, vx=1.0))
    assert seen == [("a", 1.0), ("b", 1.0), ("all", "cyan/2/VelCmd")]
    other = bus.publisher("magenta/2/VelCmd", msgs.VelCmd)
    other.put(msgs.new(msgs.VelCmd, vx=2.0))
    assert seen[-1] == ("all", "magenta/2/VelCmd") and ("a", 2.0) not in seen


def test_a_wildcard_listener_may_bind_itself_to_each_topic():
    """A listener with ``for_topic(topic)`` is called through what that returns for each matching topic (before
    and after the publisher is declared), and closing the subscription removes those callables."""
    seen, bound = [], []

    class Listener:
        def __call__(self, topic, m):
            seen.append(("call", topic))

        def for_topic(self, topic):
            bound.append(topic)
            return lambda m: seen.append(("bound", topic, m.vx))

    bus = InProcessBus()
    early = bus.publisher("cyan/1/VelCmd", msgs.VelCmd)
    sub = bus.subscribe_all("cyan/**", Listener())
    late = bus.publisher("cyan/2/VelCmd", msgs.VelCmd)
    bus.publisher("magenta/2/VelCmd", msgs.VelCmd).put(msgs.new(msgs.VelCmd, vx=9.0))
    early.put(msgs.new(msgs.VelCmd, vx=1.0))
    late.put(msgs.new(msgs.VelCmd, vx=2.0))
    assert bound == ["cyan/1/VelCmd", "cyan/2/VelCmd"]
    assert seen == [("bound", "cyan/1/VelCmd", 1.0), ("bound", "cyan/2/VelCmd", 2.0)]
    sub.close()
    assert not early.active and not late.active


def test_publish_without_subscribers_is_inactive_and_subscriptions_close():
    bus = InProcessBus()
    pub = bus.publisher("model_states", msgs.ModelStates)
    assert not pub.active
    got = []
    sub = bus.subscribe("model_states", msgs.ModelStates, got.append)
    assert pub.active
    sub.close()
    assert not pub.active


def test_type_mismatch_is_refused():
    bus = InProcessBus()
    bus.publisher("clock", msgs.Clock)
    with pytest.raises(TypeError, match="carries simatch_msgs/msg/Clock"):
        bus.subscribe("clock", msgs.VelCmd, print)
    with pytest.raises(TypeError):
        bus.publisher("clock", msgs.VelCmd)


def test_key_expressions():
    assert topics.matches("cyan/**", "cyan/2/VelCmd")
    assert topics.matches("**", "x")
    assert topics.matches("*/2/VelCmd", "magenta/2/VelCmd")
    assert not topics.matches("*/VelCmd", "cyan/2/VelCmd")
    assert topics.key("run1", "cyan/receive_from_coach") == "simatch/run1/cyan/receive_from_coach"
    assert topics.split_robot_name("cyan/2") == ("cyan", 2)
    with pytest.raises(ValueError):
        topics.split_robot_name("cyan")


def test_messages_round_trip_through_cdr_bit_for_bit():
    # float32 fields hold numbers rounded where they are made (msgs.f32s): they come back bit for bit
    vx, vy, w = msgs.f32s(0.1, -2.0 / 3.0, 1e-40)
    m = msgs.new(msgs.VelCmd, stamp=1.0 / 3.0, tick=7, vx=vx, vy=vy, w=w)
    back = msgs.decode(msgs.VelCmd, msgs.encode(m))
    assert (back.stamp, back.tick, back.vx, back.vy, back.w) == (m.stamp, m.tick, m.vx, m.vy, m.w)
    assert back.vx != 0.1 and back.vx == pytest.approx(0.1, rel=1e-7) and back.w != 0.0  # (a float32 subnormal)
    states = msgs.new(msgs.ModelStates, stamp=1.0 / 3.0, pose=np.array([1.0 / 3.0]))
    back = msgs.decode(msgs.ModelStates, msgs.encode(states))
    assert back.stamp == 1.0 / 3.0 and back.pose[0] == np.float32(1.0 / 3.0)
    exact = msgs.decode(msgs.StateFingerprint, msgs.encode(msgs.new(msgs.StateFingerprint, fingerprint=2**64 - 1)))
    assert exact.fingerprint == 2**64 - 1
    with pytest.raises(msgs.MessageError, match="malformed simatch_msgs/msg/VelCmd"):
        msgs.decode("VelCmd", b"\x00\x01\x00\x00\x01")
    assert len(msgs.names()) >= 17
    for name in msgs.names():
        msgs.decode(name, msgs.encode(msgs.new(name)))
