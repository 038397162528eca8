"""The Zenoh transport: the bus interface across processes and machines (eclipse-zenoh).

A `ZenohBus` is an in-process bus for the nodes of this process plus a bridge to the other processes of the
run, over one Zenoh session. Topics become key expressions ``simatch/<run>/<topic>``; messages travel as CDR
(the same bytes as rosbag2/ROS 2, written and read by `simatch.msgs`' generated codec), with the type in the
Zenoh encoding (``application/cdr;<type>``).

* Local delivery is exactly the in-process bus: synchronous, in subscription order, no serialisation. A
  message is encoded only when a subscriber in another process matches it.
* Remote samples are queued, in the order they arrived (callbacks run directly in the network thread, so
  one link keeps its order), and the owner of the bus delivers them with `pump` (or `take` and `deliver`,
  to look at them first, as the lockstep server does). Node code therefore runs one delivery at a time,
  needs no locks, and a run stays deterministic. (An owner may ask Zenoh's thread to deliver a feed
  itself, under the owner's lock: see `take_feed`.)
* A payload that does not decode, or that makes the receiving callback fail, is dropped and counted
  (`BusStats.malformed`); a sample the `verifier` refuses (fair play) is dropped and counted (`refused`).
  Neither ever stops the process.

Safe defaults (`zenoh_config`): multicast and gossip scouting off, explicit endpoints only, and Zenoh's
shared memory off (a process that is killed would leave segments in /dev/shm). Sessions are always closed,
also at interpreter exit: a session left open with subscribers hangs the interpreter.
"""

from __future__ import annotations

import atexit
import logging
import threading
import time
import weakref
from collections import deque
from collections.abc import Callable, Iterable
from typing import Any

import zenoh
from zenoh.handlers import Callback as _ZCallback

from .. import msgs
from . import topics as _topics
from .base import AnyCallback, BusStats, Callback
from .inproc import InProcessBus
from .zenoh_bundles import Bundles
from .zenoh_endpoints import (
    _ENCODING_PREFIX,
    Feed,
    RawPublisher,
    _Publisher,
    _RemoteSub,
    _Subscription,
    _type_of,
)
from .zenoh_session import (
    DEFAULT_ENDPOINT,
    LOW_LATENCY,
    MAX_SAMPLE,
    RUNTIME,
    TransportError,
    calm_sending_threads,
    check_run_name,
    open_session,
    zenoh_config,
)

__all__ = [
    "DEFAULT_ENDPOINT",
    "LOW_LATENCY",
    "MAX_SAMPLE",
    "RUNTIME",
    "EntryVerifier",
    "Feed",
    "RawPublisher",
    "Signer",
    "TransportError",
    "Verifier",
    "ZenohBus",
    "calm_sending_threads",
    "check_run_name",
    "open_session",
    "zenoh_config",
]

log = logging.getLogger(__name__)

#: (topic, payload, attachment) -> None if acceptable, else why it is refused
Verifier = Callable[[str, bytes, bytes | None], str | None]
#: (topic, payload) -> attachment that proves who sent it
Signer = Callable[[str, bytes], bytes]
#: (attachment of the bundle, entry topic, entry payload) -> None if the entry may be used, else why not
EntryVerifier = Callable[[bytes | None, str, bytes], str | None]


_SESSIONS: weakref.WeakSet[ZenohBus] = weakref.WeakSet()


@atexit.register
def _close_all() -> None:
    for bus in list(_SESSIONS):
        bus.close()


class ZenohBus(Bundles):
    """Publish/subscribe between the nodes of this process and, over Zenoh, every other process of ``run``.

    ``signer`` adds to each sample this process sends the proof of who sent it; ``verifier`` checks each
    sample received (the server's fair play); ``on_refused(topic, why)`` and ``on_malformed(topic, what)``
    hear about dropped samples (to log them).

    A message is encoded and sent only while a remote subscriber matches (Zenoh's matching status, kept up
    to date by a listener). Right after a publisher is declared Zenoh may not know yet who listens: a
    process that must not lose its first messages either waits for a point where it knows (the lockstep
    client calls `refresh_matching` once it has joined) or is ``eager``: it sends everything and counts
    every publisher as active (fine for a short-lived tool).

    ``drop_when_congested``: a sample for a process that does not read (stopped, hung) is dropped after a
    short wait instead of blocking the sender: a server must never be stalled by one team.

    ``prepare_on_arrival``: check and decode each data sample in Zenoh's receiving thread as it arrives
    (while the owner waits for the rest: a lockstep server decodes one team's commands while the other
    team still thinks), rather than when the owner delivers it (which leaves the cores to the teams while
    they answer: better for the latency of a real-time run with many processes).

    ``wake_on_data=False``: a waiting owner wakes only for raw (protocol) samples, not for each data sample:
    a lockstep process needs to act only when a tick opens or closes, and every wake-up costs a context
    switch on a machine where cores are scarce.

    **Bundles** (`bundle`): a process that sends many small samples at once can carry them in one Zenoh
    sample, which costs one put, one callback and one signature instead of one each:

    * ``begin_batch()`` ... ``send_batch(topic)``: what this process sends to others in between (messages
      and protocol samples) leaves as one bundle on ``topic`` (a lockstep process's answer to a tick);
    * ``declare_feed(topic, covers)`` ... ``flush_feeds([topics])``: a copy of what is published on the topics
      ``covers`` matches is gathered and sent as one bundle on ``topic`` (what a lockstep server sends to
      one team at a tick), while the topics are still sent one by one to whoever subscribes to them;
    * ``accept_bundles(pattern)``: bundles received on ``pattern`` are opened and each entry is handled as
      if it had arrived alone (checked by ``entry_verifier``: the bundle's own signature covers every entry);
    * ``take_feed(topic, covers)``: this process receives the topics ``covers`` matches from the feed on
      ``topic`` only (it declares no Zenoh subscriber of its own for them)."""

    def __init__(
        self,
        session: zenoh.Session,
        run: str = "default",
        *,
        signer: Signer | None = None,
        verifier: Verifier | None = None,
        on_refused: Callable[[str, str], None] | None = None,
        on_malformed: Callable[[str, str], None] | None = None,
        eager: bool = False,
        wake_on_data: bool = True,
        drop_when_congested: bool = False,
        prepare_on_arrival: bool = True,
        owns_session: bool = True,
        entry_verifier: EntryVerifier | None = None,
        max_sample: int | None = None,
    ):
        self.run = check_run_name(run)
        #: the largest sample this bus sends (None: no limit; `MAX_SAMPLE` on the low-latency transport)
        self.max_sample = max_sample
        self.session = session
        self.stats = BusStats()
        self.local = InProcessBus(run)
        self.signer = signer
        self.verifier = verifier
        self.entry_verifier = entry_verifier
        self.on_refused = on_refused
        self.on_malformed = on_malformed
        self.eager = eager
        self.wake_on_data = wake_on_data
        self.prepare_on_arrival = prepare_on_arrival
        self.congestion = zenoh.CongestionControl.DROP if drop_when_congested else zenoh.CongestionControl.BLOCK
        self.prefix = f"{_topics.PREFIX}/{run}/"
        self._owns = owns_session
        self._inbox: deque = deque()
        self._wake = threading.Event()
        self._queue_lock = threading.Lock()  # the inbox and its count of waking samples change together
        self._waking = 0  # waking samples in the inbox
        self._remote: list[_RemoteSub] = []
        self._pubs: dict[str, _Publisher] = {}
        self._declared: list[Any] = []  # tokens, queryables, liveliness subscribers
        self._batch: list[tuple[str, str, bytes]] | None = None  # between begin_batch and send_batch
        self._feeds: list[Feed] = []
        self._raw_pubs: dict[str, RawPublisher] = {}
        self._fed_covers: tuple[str, ...] = ()  # topics this process takes from a feed
        self._routes: dict[tuple[str, bool, bool], tuple[_RemoteSub, ...]] = {}  # bundle entry -> subscriptions
        self._routes_lock = threading.Lock()  # Zenoh's threads fill the routes; the owner changes subscriptions
        self._notices = _RemoteSub("", None, lambda *a: None, raw=True, verify=False)  # refusals inside bundles
        self._closed = False
        #: samples not sent because they were larger than ``max_sample``, by topic
        self.oversize: dict[str, int] = {}
        _SESSIONS.add(self)

    # --- the Bus interface -------------------------------------------------------------------------------
    def key(self, topic: str) -> str:
        return self.prefix + topic

    def publisher(self, topic: str, msgtype: Any, express: bool = False) -> _Publisher:
        """``express`` (this transport's own, the first call for a topic decides): a sample put outside a batch
        leaves at once from the calling thread (see `_declare_zpub`), for one sent alone whose latency counts
        (a ROS 2 bridge's command between two ticks)."""
        pub = self._pubs.get(topic)
        local = self.local.publisher(topic, msgtype)  # raises TypeError on a type clash
        if pub is not None:
            return pub
        zpub = self._declare_zpub(topic, _ENCODING_PREFIX + msgs.msgtype_name(msgtype), express=express)
        pub = _Publisher(self, topic, msgtype, local, zpub)
        self._pubs[topic] = pub
        return pub

    def subscribe(self, topic: str, msgtype: Any, callback: Callback) -> _Subscription:
        local = self.local.subscribe(topic, msgtype, callback)
        return _Subscription(self, topic, local, self._declare_remote(_RemoteSub(topic, msgtype, callback)))

    def subscribe_all(self, pattern: str, callback: AnyCallback) -> _Subscription:
        """Every message on topics matching ``pattern``, typed by its encoding; remote samples that are not
        messages (plain bytes, as the lockstep protocol sends) are left out."""
        local = self.local.subscribe_all(pattern, callback)
        return _Subscription(
            self, pattern, local, self._declare_remote(_RemoteSub(pattern, None, callback, any_type=True))
        )

    def topics(self) -> dict[str, str]:
        return self.local.topics()

    def refresh_matching(self) -> None:
        """Bring every publisher's knowledge of remote subscribers up to date now (e.g. when a process
        joins: its subscriptions arrived before its join)."""
        for pub in (*self._pubs.values(), *self._feeds, *self._raw_pubs.values()):
            pub.refresh()

    # --- raw samples (protocols built on the bus, e.g. lockstep) -------------------------------------------
    def subscribe_raw(
        self,
        topic: str,
        callback: Callable[[str, bytes, bytes | None, float], None],
        verify: bool = True,
        wakes: Callable[[str, bytes], bool] | None = None,
    ) -> _Subscription:
        """Remote samples on ``topic`` as ``callback(topic, payload, attachment, arrival)``, delivered in
        order with every other sample (``arrival``: `time.monotonic()` when it came in: the
        same clock in every process of a machine).

        ``wakes(topic, payload)``: runs in Zenoh's receiving thread as each sample is queued (before it is
        checked: it only decides when the owner looks, never what is used) and says whether the sample
        wakes an owner waiting in `wait`/`take` (by default every raw sample does). Each wake-up is a
        context switch and a GIL hand-off: a lockstep server waits for one answer per process and needs to
        look only once the last one is in."""
        rsub = _RemoteSub(topic, None, callback, raw=True, verify=verify)
        rsub.early = wakes
        return _Subscription(self, topic, None, self._declare_remote(rsub))

    def put_raw(self, topic: str, payload: bytes) -> None:
        """Send bytes to the other processes (signed like every sample of this process), for occasional
        samples (see `raw_publisher` for frequent ones); between `begin_batch` and `send_batch` they join
        the batch; feeds covering ``topic`` keep a copy."""
        if self._gather(topic, payload):
            return
        self._put_signed(topic, payload)

    def raw_publisher(self, topic: str, always: bool = True) -> RawPublisher:
        """A declared publisher of bytes on ``topic``, for samples sent often: a put on a declared Zenoh
        publisher is far cheaper than a `put_raw` (the session's put, which resolves the key each time).
        Receivers must subscribe to the exact key (not a pattern), or the server's access control may hide
        them; until a receiver is known, a put goes out as a `put_raw` (``always``) or not at all."""
        pub = self._raw_pubs.get(topic)
        if pub is None:
            pub = self._raw_pubs[topic] = RawPublisher(self, topic, self._declare_zpub(topic, express=True), always)
        return pub

    def _declare_zpub(self, topic: str, encoding: str | None = None, express: bool = False):
        """``express``: sent at once by the calling thread, not batched by Zenoh's sending task: for a sample
        that is all of what the process sends now (a bundle, a tick), it saves a thread wake-up, which on a
        busy machine is what makes the milliseconds of the latency's tail."""
        return self.session.declare_publisher(
            self.key(topic),
            encoding=zenoh.Encoding(encoding) if encoding else None,
            congestion_control=self.congestion,
            reliability=zenoh.Reliability.RELIABLE,
            allowed_destination=zenoh.Locality.REMOTE,
            express=express,
        )

    # --- sending (bundles: `Bundles`, simatch.bus.zenoh_bundles) ------------------------------------------------
    def _fits(self, topic: str, size: int) -> bool:
        """Whether a sample of ``size`` bytes may be sent (see ``max_sample``); if not, it is counted in
        ``oversize`` and logged (the first time for each topic, then every hundredth)."""
        cap = self.max_sample
        if cap is None or size <= cap:
            return True
        n = self.oversize[topic] = self.oversize.get(topic, 0) + 1
        if n == 1 or n % 100 == 0:
            log.error("not sent: a sample of %d bytes on %s (at most %d bytes; %d so far)", size, topic, cap, n)
        return False

    def _put_signed(self, topic: str, payload: bytes, count: bool = True) -> None:
        if not self._fits(topic, len(payload)):
            return
        attachment = self.signer(topic, payload) if self.signer is not None else None
        self.session.put(
            self.key(topic),
            payload,
            attachment=attachment,
            congestion_control=self.congestion,
            allowed_destination=zenoh.Locality.REMOTE,
        )
        if count:
            self.stats.published += 1

    def _add_remote(self, rsub: _RemoteSub) -> None:
        with self._routes_lock:
            self._remote.append(rsub)
            self._routes = {}

    def declare_token(self, topic: str) -> Any:
        """A liveliness token: the others see it vanish when this process ends, however it ends."""
        token = self.session.liveliness().declare_token(self.key(topic))
        self._declared.append(token)
        return token

    def watch_liveliness(self, pattern: str, callback: Callable[[str, bool], None]) -> None:
        """``callback(topic, alive)`` (in order with the other samples) when a token appears or vanishes;
        tokens present now are reported too."""
        rsub = _RemoteSub(
            pattern, None, lambda topic, payload, att, t: callback(topic, payload == b"+"), raw=True, verify=False
        )
        rsub.bundled = False
        n = len(self.prefix)

        def on_sample(sample) -> None:
            alive = b"+" if sample.kind == zenoh.SampleKind.PUT else b"-"
            self._queue((rsub, str(sample.key_expr)[n:], alive, None, "", time.monotonic(), None), True)

        rsub.zsub = self.session.liveliness().declare_subscriber(
            self.key(pattern), _ZCallback(on_sample, indirect=False), history=True
        )
        self._add_remote(rsub)

    def serve(self, topic: str, callback: Callable[[Any], None]) -> None:
        """A queryable on ``topic``: each query is queued and ``callback(query)`` runs in `deliver`, which
        must answer it (``query.reply(query.key_expr, payload)`` or ``query.reply_err(...)``)."""

        def answer(topic: str, query, attachment, arrival: float) -> None:
            try:
                callback(query)
            finally:
                query.drop()  # the query ends once answered

        rsub = _RemoteSub(topic, None, answer, raw=True, verify=False)
        n = len(self.prefix)

        def on_query(query) -> None:
            self._queue((rsub, str(query.key_expr)[n:], query, None, "", time.monotonic(), None), True)

        self._declared.append(
            self.session.declare_queryable(self.key(topic), _ZCallback(on_query, indirect=False), complete=True)
        )

    def query(self, topic: str, payload: bytes, timeout: float = 5.0) -> list[tuple[bool, bytes]]:
        """Ask the queryables on ``topic``; each answer as (ok, bytes). Blocks up to ``timeout`` seconds."""
        attachment = self.signer(topic, payload) if self.signer is not None else None
        out = []
        for reply in self.session.get(self.key(topic), payload=payload, attachment=attachment, timeout=timeout):
            if reply.ok is not None:
                out.append((True, reply.ok.payload.to_bytes()))
            else:
                out.append((False, reply.err.payload.to_bytes()))
        return out

    # --- receiving ------------------------------------------------------------------------------------------
    def _declare_remote(self, rsub: _RemoteSub) -> _RemoteSub:
        if not rsub.raw:
            rsub.wakes = self.wake_on_data
        if "*" not in rsub.topic and any(_topics.matches(c, rsub.topic) for c in self._fed_covers):
            rsub.fed = True  # served by the feed taken with take_feed
            self._add_remote(rsub)
            return rsub
        n = len(self.prefix)
        clock = time.monotonic
        with_encoding = rsub.any_type
        prepare = None if rsub.raw or not self.prepare_on_arrival else self._prepare

        def on_sample(sample) -> None:
            att = sample.attachment
            topic, payload = str(sample.key_expr)[n:], sample.payload.to_bytes()
            attachment = att.to_bytes() if att is not None else None
            encoding = str(sample.encoding) if with_encoding else ""
            if with_encoding and not encoding.startswith(_ENCODING_PREFIX):
                return  # not a message (e.g. a lockstep protocol sample)
            # checked and decoded here, in Zenoh's thread, while the owner is typically waiting: off its path
            pre = prepare(rsub, topic, payload, attachment, encoding) if prepare is not None else None
            self._queue((rsub, topic, payload, attachment, encoding, clock(), pre), _wakes(rsub, topic, payload))

        rsub.zsub = self.session.declare_subscriber(
            self.key(rsub.topic), _ZCallback(on_sample, indirect=False), allowed_origin=zenoh.Locality.REMOTE
        )
        self._add_remote(rsub)
        return rsub

    def _prepare(self, rsub: _RemoteSub, topic: str, payload: bytes, attachment, encoding: str):
        """(why refused or None, message or None, decoding error or None) of a data sample."""
        try:
            if self.verifier is not None and rsub.verify:
                why = self.verifier(topic, payload, attachment)
                if why is not None:
                    return (why, None, None)
            return (None, msgs.decode(rsub.msgtype or _type_of(encoding), payload), None)
        except msgs.MessageError as exc:
            return (None, None, exc)
        except Exception:  # never fail in Zenoh's thread: the owner will try again and report
            return None

    def _drop_remote(self, rsub: _RemoteSub) -> None:
        rsub.closed = True
        if rsub in self._remote:
            with self._routes_lock:
                self._remote.remove(rsub)
                self._routes = {}
            if rsub.zsub is not None and not self._closed:
                try:
                    rsub.zsub.undeclare()
                except zenoh.ZError:
                    pass

    # --- the owner's side of the inbox ---------------------------------------------------------------------------
    def _queue(self, item: tuple, wakes: bool) -> None:
        with self._queue_lock:
            self._inbox.append(item)
            if wakes:
                self._waking += 1
                self._wake.set()

    def _queue_all(self, items: list) -> None:
        with self._queue_lock:
            self._inbox.extend(items)
            waking = sum(1 for item in items if _wakes(item[0], item[1], item[2]))
            if waking:
                self._waking += waking
                self._wake.set()

    def wait(self, timeout: float | None) -> bool:
        """Block until a waking remote sample is queued (True; see ``wake_on_data``) or ``timeout`` seconds
        pass (False)."""
        with self._queue_lock:
            if self._waking:
                return True
            self._wake.clear()
        return self._wake.wait(timeout)

    def take(self, timeout: float | None = 0.0) -> list:
        """Every queued remote sample, oldest first, waiting up to ``timeout`` seconds for a waking one (see
        `wait`) if none is queued."""
        if timeout != 0.0:
            self.wait(timeout)
        with self._queue_lock:
            out = list(self._inbox)
            self._inbox.clear()
            self._waking = 0
        return out

    def deliver(self, items: Iterable) -> int:
        """Check, decode and hand samples (from `take`) to their callbacks, in the given order."""
        n = 0
        stats = self.stats
        for rsub, topic, payload, attachment, encoding, arrival, pre in items:
            if rsub.closed:
                continue
            if rsub.raw:
                if pre is not None:  # from a bundle: checked when it was opened
                    why, _, error = pre
                    if error is not None:
                        self._malformed(topic, error)
                        continue
                elif rsub.verify and self.verifier is not None:
                    why = self.verifier(topic, payload, attachment)
                else:
                    why = None
                if why is not None:
                    self._refused(topic, why)
                    continue
                rsub.callback(topic, payload, attachment, arrival)
                n += 1
                continue
            if pre is None:
                pre = self._prepare(rsub, topic, payload, attachment, encoding) or (None, None, None)
            why, msg, error = pre
            if why is not None:
                self._refused(topic, why)
                continue
            try:
                if error is not None:
                    raise error
                if msg is None:
                    msg = msgs.decode(rsub.msgtype or _type_of(encoding), payload)
                if rsub.any_type:
                    rsub.callback(topic, msg)
                else:
                    rsub.callback(msg)
            except Exception as exc:  # a bad payload (or one a node cannot use) never stops the process
                self._malformed(topic, exc)
                continue
            stats.delivered += 1
            n += 1
        return n

    def _refused(self, topic: str, why: str) -> None:
        self.stats.refused += 1
        if self.on_refused is not None:
            self.on_refused(topic, why)
        else:
            log.warning("refused a sample on %s: %s", topic, why)

    def _malformed(self, topic: str, exc: Exception) -> None:
        stats = self.stats
        stats.malformed += 1
        stats.malformed_by_topic[topic] = stats.malformed_by_topic.get(topic, 0) + 1
        what = str(exc) if isinstance(exc, msgs.MessageError) else f"{type(exc).__name__} while handling it: {exc}"
        if self.on_malformed is not None:
            self.on_malformed(topic, what)
        elif stats.malformed_by_topic[topic] in (1, 10, 100, 1000):
            log.warning(
                "dropped a malformed sample on %s (%d so far): %s", topic, stats.malformed_by_topic[topic], what
            )

    def pump(self, timeout: float | None = 0.0) -> int:
        """Deliver every queued remote sample (waiting up to ``timeout`` for one); returns how many."""
        return self.deliver(self.take(timeout))

    # --- lifetime --------------------------------------------------------------------------------------------
    def close(self) -> None:
        if self._closed:
            return
        self._closed = True
        for rsub in self._remote:
            rsub.closed = True
        self.local.close()
        try:
            for thing in reversed(self._declared):
                try:
                    thing.undeclare()
                except zenoh.ZError:
                    pass
            for rsub in self._remote:
                if rsub.zsub is not None:
                    try:
                        rsub.zsub.undeclare()
                    except zenoh.ZError:
                        pass
            for pub in (*self._pubs.values(), *self._feeds, *self._raw_pubs.values()):
                pub.close()
        finally:
            self._feeds.clear()
            self._raw_pubs.clear()
            self._remote.clear()
            self._declared.clear()
            self._pubs.clear()
            if self._owns:
                try:
                    self.session.close()
                except zenoh.ZError:
                    pass
            _SESSIONS.discard(self)

    def __enter__(self) -> ZenohBus:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def _wakes(rsub: _RemoteSub, topic: str, payload) -> bool:
    """Whether a sample being queued wakes the owner (in Zenoh's thread: never raises)."""
    early = rsub.early
    if early is None:
        return rsub.wakes
    try:
        return bool(early(topic, payload))
    except Exception:  # the owner will look at it anyway
        log.exception("deciding whether a sample on %s wakes the owner failed", topic)
        return True
