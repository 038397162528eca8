"""Bundles on a `ZenohBus` (`simatch.bus.bundle`): many small samples carried in one Zenoh sample, which costs
one put, one callback and one signature instead of one each (see the `ZenohBus` docstring: batches, feeds,
accepted bundles and feeds taken)."""

from __future__ import annotations

import logging
import time
from collections.abc import Callable, Collection, Sequence

import zenoh
from zenoh.handlers import Callback as _ZCallback

from .. import msgs
from . import bundle as _bundle
from . import topics as _topics
from .sharing import share_equal_lists
from .zenoh_endpoints import _ENCODING_PREFIX, _UNCHECKED, Feed, _type_of

log = logging.getLogger("simatch.bus.zenoh_bus")


class Bundles:
    """The bundle methods of `ZenohBus` (a base class of it: they share its state)."""

    def _gather(self, topic: str, payload: bytes) -> bool:
        """Copy a protocol sample into the feeds that cover it; True if it joined the batch instead of
        leaving now."""
        for feed in self._feeds:
            if feed.matching and feed.covering(topic):
                feed.entries.append((topic, "", payload))
        if self._batch is not None:
            self._batch.append((topic, "", payload))
            self.stats.published += 1
            return True
        return False

    def begin_batch(self) -> None:
        """From now until `send_batch`, what this process sends to others is gathered, not sent."""
        self._batch = []

    def send_batch(self, topic: str) -> int:
        """Send what was gathered since `begin_batch` as one bundle on ``topic`` (through `raw_publisher`:
        its receivers subscribe to ``topic`` exactly); returns how many entries it carried."""
        entries, self._batch = self._batch, None
        if entries:
            pub = self.raw_publisher(topic)
            for run in self._runs(topic, entries):
                pub.put(_bundle.pack(run), count=False)
        return len(entries or ())

    def _runs(self, topic: str, entries: list) -> list[list]:
        """The entries of a bundle on ``topic`` in runs that each fit in a sample (one run, nearly always)."""
        cap = self.max_sample
        if cap is None or sum(map(_bundle.size, entries)) + len(_bundle.MAGIC) <= cap:
            return [entries]
        runs, too_large = _bundle.split(entries, cap)
        for entry in too_large:
            self._fits(entry[0], _bundle.size(entry))
        return runs

    def declare_feed(self, topic: str, covers: Sequence[str]) -> Feed:
        """A feed on ``topic`` of what is published on the topics ``covers`` matches (see the class)."""
        feed = Feed(topic, covers, self._declare_zpub(topic, express=True))
        self._feeds.append(feed)
        for pub in self._pubs.values():
            if feed.covering(pub.topic):
                pub.feeds.append(feed)
        return feed

    def flush_feeds(self, only: Collection[str] | None = None) -> None:
        """Send each feed's gathered entries as one bundle (feeds nobody listens to gather nothing); with
        ``only``, just the feeds on those topics (the others keep gathering)."""
        signer = self.signer
        ready = []
        for feed in self._feeds:
            if only is not None and feed.topic not in only:
                continue
            entries, feed.entries = feed.entries, []
            if not (entries and feed.matching):
                continue
            for run in self._runs(feed.topic, entries):
                data = _bundle.pack(run)
                ready.append((feed, data, signer(feed.topic, data) if signer is not None else None))
        # every feed packed and signed before the first leaves: the receivers start (nearly) together, and
        # a receiver woken by the first put does not hold up the others' packing
        for feed, data, attachment in ready:
            try:
                feed._z.put(data, attachment=attachment)
            except zenoh.ZError as exc:
                log.debug("put on %s failed: %s", feed.topic, exc)
                continue
            self.stats.published += 1

    def accept_bundles(self, pattern: str, verify: bool = True) -> None:
        """Open the bundles that arrive on ``pattern``: each entry goes to this process's subscriptions as if
        it had arrived alone (to those a feed serves if ``pattern`` is the feed taken by `take_feed`, else
        to the others). With ``verify``, the bundle is checked by ``verifier`` and each entry by
        ``entry_verifier``; a broken bundle is dropped whole and counted as malformed."""
        self._declare_bundles(pattern, fed=False, verify=verify)

    def take_feed(self, topic: str, covers: Sequence[str], handle: Callable[[], None] | None = None) -> None:
        """Receive the topics ``covers`` matches only from the feed on ``topic`` (see `declare_feed`); call it
        before subscribing. Subscriptions to those exact topics (no wildcard) then declare nothing in Zenoh,
        so nothing arrives twice; the feed's sender is not checked (like every sample from the server).

        ``handle``: called in Zenoh's receiving thread once a feed sample is queued, instead of waking the
        owner: an owner whose only work is to answer its feed (a lockstep client) saves a thread hand-off
        per sample. It must deliver under the same lock as the owner's own deliveries."""
        self._fed_covers = (*self._fed_covers, *covers)
        self._declare_bundles(topic, fed=True, verify=False, handle=handle)

    def _declare_bundles(self, pattern: str, fed: bool, verify: bool, handle: Callable[[], None] | None = None) -> None:
        n = len(self.prefix)
        clock = time.monotonic
        notices = self._notices

        def on_sample(sample) -> None:
            att = sample.attachment
            topic, payload = str(sample.key_expr)[n:], sample.payload.to_bytes()
            attachment = att.to_bytes() if att is not None else None
            arrival = clock()
            try:
                items = self._open_bundle(topic, payload, attachment, arrival, fed, verify)
            except Exception as exc:  # never fail in Zenoh's thread: the owner reports it
                items = [(notices, topic, payload, None, "", arrival, (None, None, exc))]
            if handle is None:
                self._queue_all(items)
                return
            with self._queue_lock:
                self._inbox.extend(items)
            try:
                handle()
            except Exception:  # never fail in Zenoh's thread: wake the owner to deal with it
                log.exception("handling a feed sample failed")
                self._wake.set()

        zsub = self.session.declare_subscriber(
            self.key(pattern), _ZCallback(on_sample, indirect=False), allowed_origin=zenoh.Locality.REMOTE
        )
        self._declared.append(zsub)

    def _open_bundle(self, topic: str, payload: bytes, attachment, arrival: float, fed: bool, verify: bool) -> list:
        """The inbox items of one bundle: its entries, each with what `deliver` needs to know
        (``pre``: why refused / decoded message / error), or one notice if the bundle is refused or broken."""
        notices = self._notices
        if verify and self.verifier is not None:
            why = self.verifier(topic, payload, attachment)
            if why is not None:
                return [(notices, topic, payload, None, "", arrival, (why, None, None))]
        try:
            entries = _bundle.unpack(payload)
        except _bundle.BundleError as exc:
            return [(notices, topic, payload, None, "", arrival, (None, None, msgs.MessageError(str(exc))))]
        check = self.entry_verifier if verify else None
        decode = self.prepare_on_arrival
        routes = self._routes
        out = []
        made = [] if fed and decode else None  # a feed's messages, to share their equal parts (`sharing`)
        for entry_topic, msgtype, data in entries:
            raw = not msgtype
            subs = routes.get((entry_topic, raw, fed))
            if subs is None:
                subs = self._route(entry_topic, raw, fed)
            if not subs:
                continue
            if check is not None:
                why = check(attachment, entry_topic, data)
                if why is not None:
                    out.append((notices, entry_topic, data, None, "", arrival, (why, None, None)))
                    continue
            encoding = "" if raw else _ENCODING_PREFIX + msgtype
            decoded = None  # (type, pre): decoded once for every subscription of that type, and the
            for rsub in subs:  # message shared by them, as the in-process bus shares one message object
                pre = _UNCHECKED
                if decode and not raw:
                    try:
                        name = rsub.msgtype or _type_of(encoding)
                        if decoded is None or decoded[0] != name:
                            decoded = (name, (None, msgs.decode(name, data), None))
                            if made is not None:
                                made.append((decoded[1][1], data))
                        pre = decoded[1]
                    except msgs.MessageError as exc:
                        pre = (None, None, exc)
                out.append((rsub, entry_topic, data, None, encoding, arrival, pre))
        if made:
            share_equal_lists(made)
        return out

    def _route(self, topic: str, raw: bool, fed: bool) -> tuple:
        """The subscriptions an entry on ``topic`` goes to (remembered until subscriptions change)."""
        with self._routes_lock:
            subs = tuple(
                r
                for r in self._remote
                if r.raw == raw and r.fed == fed and r.bundled and not r.closed and _topics.matches(r.topic, topic)
            )
            self._routes[(topic, raw, fed)] = subs
        return subs
