"""The in-process transport: synchronous delivery of message objects, no serialisation, no threads.

A ``put`` calls every matching subscriber right away, in the order the subscriptions were made, so an
embedded run is deterministic and costs one Python call per delivery. Wildcard subscriptions are resolved
once, when a publisher is declared, never per message: the listener ``f(topic, msg)`` is bound to each
topic then, by its own ``f.for_topic(topic) -> g`` (``g(msg)``) where it has one, else by a partial.
"""

from __future__ import annotations

from functools import partial
from itertools import islice
from typing import Any

from . import topics as _topics
from .base import AnyCallback, BusStats, Callback


class _Publisher:
    """A topic's sending end: ``put(msg)`` delivers to every subscriber, in subscription order. ``active``
    (whether anybody listens) is a plain attribute, set again whenever a subscriber comes or goes: it is
    read before building a message that nobody may want, so it costs no call. ``_one``
    is the subscriber when there is exactly one (most topics: a robot's commands, its perception, the
    model states), called without the loop over the list."""

    __slots__ = ("topic", "msgtype", "_bus", "_callbacks", "_one", "active")

    def __init__(self, bus: InProcessBus, topic: str, msgtype: Any):
        self.topic = topic
        self.msgtype = msgtype
        self._bus = bus
        self._callbacks: list[Callback] = []
        self._one: Callback | None = None
        self.active = False

    def _rebind(self) -> None:
        callbacks = self._callbacks
        self.active = bool(callbacks)
        self._one = callbacks[0] if len(callbacks) == 1 else None

    # (a method, looked up at each call: a sender may keep the bound ``put``, and must still reach
    # subscribers that come later)
    def put(self, msg: Any) -> None:
        one = self._one
        if one is not None:
            one(msg)
            if self._one is not one:  # subscribers came or went during the call: those the loop would reach
                for cb in islice(self._callbacks, 1, None):
                    cb(msg)
            return
        for cb in self._callbacks:
            cb(msg)


class _Subscription:
    __slots__ = ("topic", "msgtype", "callback", "any_type", "_bus", "_bound")

    def __init__(self, bus: InProcessBus, topic: str, msgtype: Any, callback, any_type: bool):
        self.topic = topic
        self.msgtype = msgtype
        self.callback = callback
        self.any_type = any_type
        self._bus = bus
        self._bound: list[tuple[_Publisher, Callback]] = []

    def _bind(self, pub: _Publisher) -> None:
        if self.any_type:
            # the listener's own callable for the topic where it offers one (``for_topic``: the recorder's message
            # log finds the topic's channel once instead of per message), else a partial, not a lambda: called in
            # C, no extra Python frame
            for_topic = getattr(self.callback, "for_topic", None)
            bound: Callback = for_topic(pub.topic) if for_topic is not None else partial(self.callback, pub.topic)
        else:
            if self.msgtype is not None and pub.msgtype is not None and _name(self.msgtype) != _name(pub.msgtype):
                raise TypeError(
                    f"topic {pub.topic!r} carries {_name(pub.msgtype)}, but a subscriber expects {_name(self.msgtype)}"
                )
            bound = self.callback
        pub._callbacks.append(bound)
        pub._rebind()
        self._bound.append((pub, bound))

    def close(self) -> None:
        for pub, bound in self._bound:
            try:
                pub._callbacks.remove(bound)
            except ValueError:
                pass
            pub._rebind()
        self._bound.clear()
        if self in self._bus._subs:
            self._bus._subs.remove(self)


def _name(msgtype: Any) -> str:
    return msgtype if isinstance(msgtype, str) else getattr(msgtype, "__msgtype__", repr(msgtype))


class InProcessBus:
    """All nodes of a run in one process; ``run`` only names the run (for logs and recordings)."""

    def __init__(self, run: str = "embedded"):
        self.run = run
        self.stats = BusStats()
        self._pubs: dict[str, _Publisher] = {}
        self._subs: list[_Subscription] = []

    def publisher(self, topic: str, msgtype: Any) -> _Publisher:
        pub = self._pubs.get(topic)
        if pub is not None:
            if _name(pub.msgtype) != _name(msgtype):
                raise TypeError(f"topic {topic!r} already carries {_name(pub.msgtype)}, not {_name(msgtype)}")
            return pub
        pub = _Publisher(self, topic, msgtype)
        self._pubs[topic] = pub
        for sub in self._subs:
            if _topics.matches(sub.topic, topic):
                sub._bind(pub)
        return pub

    def subscribe(self, topic: str, msgtype: Any, callback: Callback) -> _Subscription:
        return self._add(_Subscription(self, topic, msgtype, callback, any_type=False))

    def subscribe_all(self, pattern: str, callback: AnyCallback) -> _Subscription:
        return self._add(_Subscription(self, pattern, None, callback, any_type=True))

    def _add(self, sub: _Subscription) -> _Subscription:
        self._subs.append(sub)
        for topic, pub in self._pubs.items():
            if _topics.matches(sub.topic, topic):
                sub._bind(pub)
        return sub

    def topics(self) -> dict[str, str]:
        """Every declared topic and the full name of its message type."""
        return {t: _name(p.msgtype) for t, p in self._pubs.items()}

    def close(self) -> None:
        for sub in list(self._subs):
            sub.close()
        self._pubs.clear()

    def __enter__(self) -> InProcessBus:
        return self

    def __exit__(self, *exc) -> None:
        self.close()
