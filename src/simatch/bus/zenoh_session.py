"""Opening Zenoh sessions for simatch: the configuration with simatch's safe defaults (no scouting, only the
endpoints given, no shared memory), the endpoint and transport defaults, and the tuning of Zenoh's threads.
`simatch.bus.zenoh_bus` builds the bus on such a session."""

from __future__ import annotations

import json
import os
import re
import time
from collections.abc import Sequence
from typing import Any

import zenoh

#: the endpoint a server listens on and a team connects to when none is given: loopback only
DEFAULT_ENDPOINT = "tcp/127.0.0.1:7447"


#: the largest payload a sample may carry on Zenoh's low-latency transport [bytes]: it writes each sample
#: as one frame of at most three quarters of its 64 KiB batch, and a larger one breaks the link. A bus on
#: that transport (``ZenohBus(max_sample=MAX_SAMPLE)``) sends no larger message (logged) and cuts bundles and
#: feeds into several samples below it; on the ordinary transport Zenoh fragments large samples itself.
MAX_SAMPLE = 48_000


#: ``SIMATCH_ZENOH_LOW_LATENCY=1`` in the environment: simatch's server, team and robot processes ask for
#: the low-latency transport (see `zenoh_config`). Off by default: it shortens the tail of a lockstep round
#: trip but not the real-time factor nor the real-time latency, and it caps every sample at `MAX_SAMPLE`.
LOW_LATENCY = os.environ.get("SIMATCH_ZENOH_LOW_LATENCY", "") == "1"


#: Zenoh's runtime threads in a simatch process (Zenoh reads ``ZENOH_RUNTIME`` when its runtime starts; a
#: value the user sets wins): one receiving worker instead of two. Every sample's callback needs the GIL,
#: so a second worker adds no parallelism, only wake-ups: idle workers are woken to steal the task the
#: other one just got.
RUNTIME = "(rx: (worker_threads: 1), app: (worker_threads: 1), acc: (worker_threads: 1))"


#: the names of Zenoh's sending threads (its "tx" runtime's workers)
_SENDER_THREAD = re.compile(r"^tx-\d+$")


_RUN_NAME = re.compile(r"^[A-Za-z0-9_.\-]+$")


class TransportError(RuntimeError):
    """The Zenoh session could not be opened or used (e.g. nothing listens at the endpoint)."""


def check_run_name(run: str) -> str:
    if not _RUN_NAME.match(run or ""):
        raise ValueError(f"run name {run!r}: use letters, digits, '_', '-' or '.' (it becomes a key chunk)")
    return run


def zenoh_config(
    mode: str = "peer",
    listen: Sequence[str] = (),
    connect: Sequence[str] = (),
    user: str | None = None,
    password: str | None = None,
    users_file: str | None = None,
    access_control: dict | None = None,
    low_latency: bool | None = None,
) -> zenoh.Config:
    """A Zenoh configuration with simatch's safe defaults: no scouting, only the endpoints given, no shared
    memory; ``user``/``password`` authenticate this session, ``users_file`` (a router) checks others'.

    ``low_latency`` (default: `LOW_LATENCY`): Zenoh's low-latency unicast transport, used when both ends of
    a link ask for it (a client that does not gets the ordinary transport from the same server). A sample is
    written to the socket by the thread that puts it, where the ordinary transport hands it to a sending
    thread first: one wake-up less per sample. It has no priorities (qos is off) and carries samples of at
    most `MAX_SAMPLE` bytes: give the bus on such a session ``max_sample=MAX_SAMPLE``."""
    conf = zenoh.Config()
    if low_latency is None:
        low_latency = LOW_LATENCY

    def put(key: str, value: Any) -> None:
        conf.insert_json5(key, json.dumps(value))

    put("mode", mode)
    put("scouting/multicast/enabled", False)
    put("scouting/gossip/enabled", False)
    put("listen/endpoints", list(listen))
    put("connect/endpoints", list(connect))
    put("transport/shared_memory/enabled", False)
    if low_latency:
        put("transport/unicast/lowlatency", True)
        put("transport/unicast/qos/enabled", False)
    if user is not None or users_file is not None:
        usrpwd: dict[str, Any] = {"user": user, "password": password}
        if users_file is not None:
            usrpwd["dictionary_file"] = users_file
        put("transport/auth/usrpwd", usrpwd)
    if access_control is not None:
        put("access_control", access_control)
    return conf


def open_session(conf: zenoh.Config, wait: float = 0.0, what: str = "") -> zenoh.Session:
    """Open a session, retrying for up to ``wait`` seconds (e.g. while the server starts)."""
    os.environ.setdefault("ZENOH_RUNTIME", RUNTIME)  # before Zenoh's runtime starts (its first session)
    deadline = time.monotonic() + wait
    while True:
        try:
            return zenoh.open(conf)
        except zenoh.ZError as exc:
            if time.monotonic() >= deadline:
                first = str(exc).split(" at ", 1)[0]
                raise TransportError(f"cannot open the Zenoh session{' ' + what if what else ''}: {first}") from None
            time.sleep(0.2)


def calm_sending_threads() -> int:
    """Make Zenoh's sending threads of this process ``SCHED_BATCH`` (Linux; elsewhere nothing): they still
    get their share of the CPU, but waking one no longer preempts the thread that woke it. On the ordinary
    transport every put wakes the sending thread: a lockstep server putting its feeds must not be preempted
    after the first one while the other teams' feeds wait. The sending thread runs once the putting thread
    waits (or on an idle core).
    Returns how many threads were changed."""
    if not hasattr(os, "sched_setscheduler") or not os.path.isdir("/proc/self/task"):
        return 0
    changed = 0
    for tid in os.listdir("/proc/self/task"):
        try:
            with open(f"/proc/self/task/{tid}/comm", encoding="utf-8") as f:
                name = f.read().strip()
            if _SENDER_THREAD.match(name):
                os.sched_setscheduler(int(tid), os.SCHED_BATCH, os.sched_param(0))
                changed += 1
        except (OSError, ValueError):  # the thread ended meanwhile, or the system does not allow it
            continue
    return changed
