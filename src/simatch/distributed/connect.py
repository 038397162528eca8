"""How a joining process (a team, a robot, a ROS bridge, an observer) opens its session to the server, and
why it cannot.

Zenoh answers a refused credential and a server that is not there with the same error ("unable to connect"),
so a process that only retried would wait out its whole ``--wait`` with a wrong key and then say neither. The two are
told apart by looking at the transport itself: when something accepts a TCP connection at the server's
address but Zenoh's handshake still fails, the server is up and refuses this credential (usrpwd
authentication fails in the handshake), which waiting will not change: that is said at once, in one line.
When nothing listens there, the server may still be starting: the process says so once and waits for it,
then gives up with a message that says nothing answered."""

from __future__ import annotations

import socket
import time
from collections.abc import Callable
from pathlib import Path

import zenoh

from ..bus.zenoh_bus import TransportError, open_session, zenoh_config
from .credentials import Credential

#: a handshake refused this many times in a row, with the address accepting connections, is a refusal
#: of the credential (not a server that was just then starting its transport)
REFUSALS = 3
RETRY_S = 0.2


class ConnectError(RuntimeError):
    """The server refused this process's credential, or no server answered in time."""

    def __init__(self, message: str, refused: bool):
        super().__init__(message)
        self.refused = refused


def tcp_address(endpoint: str) -> tuple[str, int] | None:
    """(host, port) of a Zenoh ``tcp/HOST:PORT`` endpoint (IPv6 as ``tcp/[::1]:PORT``); None for other
    transports, whose reachability is not probed."""
    proto, _, rest = endpoint.partition("/")
    if proto != "tcp" or ":" not in rest:
        return None
    host, _, port = rest.split("#", 1)[0].rpartition(":")
    try:
        return host.strip("[]"), int(port)
    except ValueError:
        return None


def listening(address: tuple[str, int], timeout: float = 1.0) -> bool:
    """Whether something accepts TCP connections at ``address``."""
    try:
        with socket.create_connection(address, timeout=timeout):
            return True
    except OSError:
        return False


def open_server_session(
    cred: Credential,
    connect: str,
    key: Path | str,
    wait: float,
    say: Callable[[str], None] | None = None,
) -> zenoh.Session:
    """A Zenoh client session to the server at ``connect`` with credential ``cred`` (read from ``key``).

    Raises `ConnectError` with ``refused=True`` within about a second when the server refuses the
    credential, or with ``refused=False`` after ``wait`` seconds in which no server listened there; ``say``
    hears once that the process is waiting for a server that is not there yet."""
    conf = zenoh_config("client", connect=[connect], user=cred.name, password=cred.secret)
    address = tcp_address(connect)
    deadline = time.monotonic() + wait
    refusals, told = 0, False
    while True:
        try:
            return open_session(conf)
        except TransportError as exc:
            failure = exc
        if address is not None and listening(address):
            refusals += 1
            if refusals >= REFUSALS:
                raise ConnectError(
                    f"the server at {connect} refused the credential in {key} (user {cred.name!r}): its secret "
                    f"is not the one this server holds for {cred.name}; use the {cred.name}.key file of this "
                    "run's server",
                    refused=True,
                )
        else:
            refusals = 0
            if not told and say is not None and address is not None and wait > 0:
                say(f"no server listens at {connect} yet; waiting up to {wait:.0f} s for one")
                told = True
        if time.monotonic() >= deadline:
            if address is None:
                raise ConnectError(
                    f"{failure} (is the server running, and is {key} the right credential?)", refused=False
                )
            raise ConnectError(
                f"no simatch server answers at {connect} (nothing listened there for {wait:.0f} s): is it "
                "running, and is the address right?",
                refused=False,
            )
        time.sleep(RETRY_S)
