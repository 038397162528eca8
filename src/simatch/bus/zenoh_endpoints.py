"""The Zenoh side of a `ZenohBus`'s subscriptions and publishers (`simatch.bus.zenoh_bus`): what a remote
subscription queues, and the publishers that send only while somebody in another process listens."""

from __future__ import annotations

import logging
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any

import zenoh
from zenoh.handlers import Callback as _ZCallback

from .. import msgs
from . import topics as _topics

if TYPE_CHECKING:
    from .zenoh_bus import ZenohBus

log = logging.getLogger("simatch.bus.zenoh_bus")

#: the ``pre`` of an inbox item that was neither refused nor decoded in advance (see `ZenohBus.deliver`)
_UNCHECKED = (None, None, None)


_ENCODING_PREFIX = "application/cdr;"


class _RemoteSub:
    """One subscription's Zenoh side: what arrives is queued, then decoded and delivered by the owner."""

    __slots__ = (
        "topic",
        "msgtype",
        "callback",
        "any_type",
        "raw",
        "verify",
        "closed",
        "zsub",
        "wakes",
        "fed",
        "bundled",
        "early",
        "__weakref__",
    )

    def __init__(
        self,
        topic: str,
        msgtype: Any,
        callback,
        any_type: bool = False,
        raw: bool = False,
        verify: bool = True,
        wakes: bool = True,
    ):
        self.topic = topic
        self.msgtype = None if msgtype is None else msgs.msgtype_name(msgtype)
        self.callback = callback
        self.any_type = any_type
        self.raw = raw
        self.verify = verify
        self.wakes = wakes
        #: ``early(topic, payload) -> bool``, run in Zenoh's thread as a sample is queued: whether it wakes
        #: the owner (None: ``wakes`` says)
        self.early: Callable[[str, bytes], bool] | None = None
        self.closed = False
        self.zsub = None
        self.fed = False  # served by a feed (`ZenohBus.take_feed`), not by a Zenoh subscriber of its own
        self.bundled = True  # bundle entries may reach it (not liveliness: only Zenoh tells who is alive)


class _Subscription:
    __slots__ = ("topic", "_local", "_remote", "_bus")

    def __init__(self, bus: ZenohBus, topic: str, local, remote: _RemoteSub):
        self.topic = topic
        self._bus = bus
        self._local = local
        self._remote = remote

    def close(self) -> None:
        if self._local is not None:
            self._local.close()
        self._bus._drop_remote(self._remote)


class _Matching:
    __slots__ = ()
    """Whether a subscriber in another process matches a Zenoh publisher (kept up to date by Zenoh's
    matching listener)."""

    def _watch(self, zpub) -> None:
        self._z = zpub
        self.matching = False

        def on_status(status) -> None:
            self.matching = status.matching

        self._listener = zpub.declare_matching_listener(_ZCallback(on_status, indirect=False))
        self.refresh()

    def refresh(self) -> None:
        """Ask Zenoh now whether remote subscribers match (the listener may not have spoken yet)."""
        try:
            self.matching = self._z.matching_status.matching
        except zenoh.ZError:  # the session is closing
            self.matching = False

    def close(self) -> None:
        for thing in (self._listener, self._z):
            try:
                thing.undeclare()
            except zenoh.ZError:
                pass


class Feed(_Matching):
    """What this process sends to one kind of receiver, gathered and sent as one bundle when the owner
    flushes it (`ZenohBus.flush_feeds`): a copy of every message published on a topic ``covers`` matches,
    and of every protocol sample (`ZenohBus.put_raw`) on such a topic; kept only while somebody listens."""

    def __init__(self, topic: str, covers: Sequence[str], zpub):
        self.topic = topic
        self.covers = tuple(covers)
        self.entries: list[tuple[str, str, bytes]] = []
        self._covered: dict[str, bool] = {}  # topic -> covered: a raw sample (the tick) asks at every tick
        self._watch(zpub)

    def covering(self, topic: str) -> bool:
        known = self._covered.get(topic)
        if known is None:
            known = any(_topics.matches(c, topic) for c in self.covers)
            if len(self._covered) < 4096:
                self._covered[topic] = known
        return known


class RawPublisher(_Matching):
    """Bytes sent often on one topic (`ZenohBus.raw_publisher`), signed like every sample of the process."""

    def __init__(self, bus: ZenohBus, topic: str, zpub, always: bool):
        self.topic = topic
        self._bus = bus
        self.always = always
        self._watch(zpub)

    def put(self, payload: bytes, count: bool = True) -> None:
        """``count``: counts as a published sample (not a bundle, whose entries were counted)."""
        bus = self._bus
        if bus._gather(self.topic, payload):
            return
        if not bus._fits(self.topic, len(payload)):
            return
        if not self.matching:
            if self.always:
                bus._put_signed(self.topic, payload, count)
            return
        signer = bus.signer
        try:
            self._z.put(payload, attachment=signer(self.topic, payload) if signer is not None else None)
        except zenoh.ZError as exc:
            log.debug("put on %s failed: %s", self.topic, exc)
            return
        if count:
            bus.stats.published += 1


class _Publisher(_Matching):
    __slots__ = ("topic", "msgtype", "typename", "feeds", "_local", "_z", "_bus", "matching", "_listener")

    def __init__(self, bus: ZenohBus, topic: str, msgtype: Any, local, zpub):
        self.topic = topic
        self.msgtype = msgtype
        self.typename = msgs.msgtype_name(msgtype)
        self._bus = bus
        self._local = local
        #: the feeds that carry this topic too
        self.feeds: list[Feed] = [f for f in bus._feeds if f.covering(topic)]
        self._watch(zpub)

    @property
    def active(self) -> bool:
        return self.matching or self._bus.eager or self._local.active or any(f.matching for f in self.feeds)

    def put(self, msg: Any) -> None:
        local = self._local
        if local._callbacks:
            local.put(msg)
        bus = self._bus
        remote = self.matching or bus.eager
        fed = [f for f in self.feeds if f.matching] if self.feeds else ()
        if remote or fed:
            data = msgs.encode(msg)
            for feed in fed:
                feed.entries.append((self.topic, self.typename, data))
            if not remote:
                return
            if not bus._fits(self.topic, len(data)):
                return
            batch = bus._batch
            if batch is not None:
                batch.append((self.topic, self.typename, data))
                bus.stats.published += 1
                return
            signer = bus.signer
            try:
                if signer is None:
                    self._z.put(data)
                else:
                    self._z.put(data, attachment=signer(self.topic, data))
            except zenoh.ZError as exc:
                log.debug("put on %s failed: %s", self.topic, exc)
                return
            bus.stats.published += 1


def _type_of(encoding: str) -> str:
    if not encoding.startswith(_ENCODING_PREFIX):
        raise msgs.MessageError(f"sample with encoding {encoding or '(none)'!r}: expected {_ENCODING_PREFIX}<type>")
    name = encoding[len(_ENCODING_PREFIX) :]
    if name not in msgs.typestore.types:
        raise msgs.MessageError(f"sample of unknown type {name!r}")
    return name
