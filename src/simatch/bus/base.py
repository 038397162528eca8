"""The bus interface every node is written against; transports implement it.

A node declares what it publishes and subscribes to, in a few lines, and never learns which transport
carries its messages: the same node code runs in process (embedded runs) and across processes (Zenoh).

Callbacks receive message objects of the declared type. Messages are read-only by convention: in process
the very same object reaches every subscriber.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, Protocol


@dataclass
class BusStats:
    """Counters a transport keeps; `malformed` counts payloads dropped because they did not decode."""

    published: int = 0
    delivered: int = 0
    malformed: int = 0
    refused: int = 0
    malformed_by_topic: dict[str, int] = field(default_factory=dict)


class Publisher(Protocol):
    topic: str
    msgtype: Any

    @property
    def active(self) -> bool:
        """Whether anybody listens; a producer may skip building a message nobody will read."""

    def put(self, msg: Any) -> None: ...


class Subscription(Protocol):
    topic: str

    def close(self) -> None: ...


Callback = Callable[[Any], None]
AnyCallback = Callable[[str, Any], None]


class Bus(Protocol):
    """Publish/subscribe between the nodes of one run (``run`` names it on a shared network)."""

    run: str
    stats: BusStats

    def publisher(self, topic: str, msgtype: Any) -> Publisher: ...

    def subscribe(self, topic: str, msgtype: Any, callback: Callback) -> Subscription:
        """Deliver every message published on ``topic`` (wildcards ``*``/``**`` allowed) to ``callback``."""

    def subscribe_all(self, pattern: str, callback: AnyCallback) -> Subscription:
        """Deliver ``(topic, message)`` for every topic matching ``pattern``, whatever its type."""

    def close(self) -> None: ...
