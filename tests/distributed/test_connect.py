"""A joining process says at once when the server refuses its credential, and tells that apart from a
server that is not there (real server and team processes over real Zenoh on loopback)."""

from __future__ import annotations

import secrets
import time

import pytest

from simatch.bus.zenoh_bus import zenoh_config
from simatch.distributed.connect import ConnectError, listening, open_server_session, tcp_address
from simatch.distributed.credentials import Credential

from .cluster import free_port


def _wrong_key(tmp_path, name="magenta"):
    """A well-formed credential file whose secret no server holds."""
    path = tmp_path / f"{name}-wrong.key"
    path.write_text(f"{name}:{secrets.token_hex(16)}\n")
    path.chmod(0o600)
    return path


def _await_listening(endpoint: str, server, procs, timeout: float = 90.0) -> None:
    deadline = time.monotonic() + timeout
    while not listening(tcp_address(endpoint), timeout=0.5):
        assert server.poll() is None, f"the server ended:\n{procs.stderr(server)}"
        assert time.monotonic() < deadline, "the server never listened"
        time.sleep(0.2)


def test_a_refused_credential_is_said_at_once_in_one_line(procs, tmp_path):
    server = procs.server("msl_5v5", "--duration", "60", "--deadline", "120")
    _await_listening(procs.endpoint, server, procs)
    key = _wrong_key(tmp_path)
    start = time.monotonic()
    team = procs.start(
        "team",
        "magenta",
        "--connect",
        procs.endpoint,
        "--run",
        procs.run,
        "--key",
        str(key),
        "--wait",
        "120",
        name="team-wrong-key",
    )
    code = procs.wait(team, timeout=100)
    took = time.monotonic() - start
    err = procs.stderr(team)
    assert code != 0
    lines = [line for line in err.splitlines() if "refused the credential" in line]
    assert len(lines) == 1, err
    assert str(key) in lines[0] and "'magenta'" in lines[0]
    assert took < 60, f"told after {took:.1f} s of a 120 s wait: the refusal was waited out\n{err}"


def test_a_server_that_is_not_there_is_told_apart(procs, tmp_path):
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    team = procs.start(
        "team",
        "magenta",
        "--connect",
        endpoint,
        "--run",
        "nobody",
        "--key",
        str(_wrong_key(tmp_path)),
        "--wait",
        "2",
        name="team-no-server",
    )
    assert procs.wait(team, timeout=60) != 0
    err = procs.stderr(team)
    assert f"no server listens at {endpoint} yet" in err
    assert f"no simatch server answers at {endpoint}" in err
    assert "refused the credential" not in err


def test_the_right_credential_opens_and_a_wrong_one_is_refused(tmp_path):
    """The function every joining process uses (teams, robots, ROS 1 and ROS 2 bridges, observers),
    against a real Zenoh router that authenticates as the server does."""
    users = tmp_path / "users.txt"
    users.write_text("magenta:goodsecret\n")
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    import zenoh

    router = zenoh.open(zenoh_config("router", listen=[endpoint], user="server", password="s", users_file=str(users)))
    try:
        session = open_server_session(Credential("magenta", "goodsecret"), endpoint, "magenta.key", wait=5)
        session.close()
        with pytest.raises(ConnectError, match="refused the credential in magenta.key") as caught:
            open_server_session(Credential("magenta", "badsecret"), endpoint, "magenta.key", wait=30)
        assert caught.value.refused
    finally:
        router.close()


@pytest.mark.parametrize(
    "endpoint,address",
    [
        ("tcp/127.0.0.1:7447", ("127.0.0.1", 7447)),
        ("tcp/[::1]:7447", ("::1", 7447)),
        ("tcp/localhost:7447#iface=lo", ("localhost", 7447)),
        ("udp/127.0.0.1:7447", None),
        ("unixsock-stream//tmp/z.sock", None),
        ("tcp/nonsense", None),
    ],
)
def test_tcp_addresses_of_endpoints(endpoint, address):
    assert tcp_address(endpoint) == address
