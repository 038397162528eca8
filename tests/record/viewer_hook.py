"""A stand-in for a viewer's replay extension: counts what the replay publishes on the bus it offers."""

from __future__ import annotations

import contextlib

SEEN: dict = {}


class CountingViewer:
    def add_arguments(self, parser) -> None:
        parser.add_argument("--count", action="store_true", help="count the replayed messages")

    def attach(self, player, args):
        if not args.count:
            return contextlib.nullcontext()
        return self._watch(player)

    @contextlib.contextmanager
    def _watch(self, player):
        SEEN.clear()
        SEEN["scene"] = player.scene.name
        sub = player.bus.subscribe_all("**", lambda topic, msg: SEEN.__setitem__(topic, SEEN.get(topic, 0) + 1))
        try:
            yield
        finally:
            sub.close()
            SEEN["done"] = player.done
