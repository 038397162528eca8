"""Per-team credentials: who a process is, proved to Zenoh (user/password) and on every sample it sends.

A credential is a name (a team, or ``admin`` for the organiser's privileged tools) and a random secret.
The server keeps one file per name in its credentials folder (``<name>.key``, text ``name:secret``, readable
by its owner only) and creates the missing ones; the organiser hands each team its own file.

* Zenoh's user/password authentication checks the credential when a process connects to the server (a
  process without a valid one cannot connect at all), and the server's access control then limits what that
  user may subscribe to (see `fairplay`).
* Every sample a process sends carries an attachment ``SIM1 | len(name) | name | mac``, where mac is the first
  16 bytes of HMAC-SHA256(secret, run NUL topic NUL payload). The server checks it before it uses a sample,
  so it knows which team sent each command and refuses (and logs) what that team may not send.
"""

from __future__ import annotations

import hmac
import os
import secrets
import tempfile
import time
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path

ADMIN = "admin"
_MAGIC = b"SIM1"
_MAC_BYTES = 16


class CredentialError(ValueError):
    """A credential file that is missing, unreadable or not ``name:secret``."""


@dataclass(frozen=True)
class Credential:
    name: str
    secret: str  # hex

    @property
    def key(self) -> bytes:
        return bytes.fromhex(self.secret)

    def signer(self, run: str):
        """The function that signs what this process sends in ``run`` (for `ZenohBus(signer=...)`)."""
        key, head, prefix = (
            self.key,
            _MAGIC + bytes([len(self.name.encode())]) + self.name.encode(),
            run.encode() + b"\0",
        )

        def sign(topic: str, payload: bytes) -> bytes:
            return head + hmac.digest(key, prefix + topic.encode() + b"\0" + payload, "sha256")[:_MAC_BYTES]

        return sign


def default_dir(run: str) -> Path:
    """Where a server keeps (and a team on the same machine finds) the credentials of a run by default."""
    base = os.environ.get("XDG_RUNTIME_DIR") or os.path.join(tempfile.gettempdir(), f"simatch-{os.getuid()}")
    return Path(base) / "simatch" / run


def read(path: str | os.PathLike) -> Credential:
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8").strip()
    except FileNotFoundError:
        raise CredentialError(
            f"credential file {p} does not exist (the server writes one per team in its "
            f"credentials folder: use --key FILE)"
        ) from None
    except OSError as exc:
        raise CredentialError(f"credential file {p} cannot be read: {exc}") from None
    name, sep, secret = text.partition(":")
    try:
        ok = bool(sep and name and len(secret) >= 32 and bytes.fromhex(secret))
    except ValueError:
        ok = False
    if not ok:
        raise CredentialError(f"credential file {p}: expected 'name:hexsecret'")
    return Credential(name, secret)


def await_file(path: str | os.PathLike, wait: float, poll: float = 0.2) -> Credential:
    """The credential at ``path``, waiting up to ``wait`` seconds for it to appear (a server writes its
    credentials when it starts: a team started beside it may look first). A missing file at the end names
    the credentials its folder does hold: a team that is not in the run (a typing error, another scene's
    team) is told so rather than only that a file is missing."""
    p = Path(path)
    deadline = time.monotonic() + wait
    while True:
        try:
            return read(p)
        except CredentialError:
            if p.exists():
                raise
            if time.monotonic() >= deadline:
                break
        time.sleep(poll)
    held = sorted(k.stem for k in p.parent.glob("*.key")) if p.parent.is_dir() else []
    if not held:
        raise CredentialError(
            f"credential file {p} does not exist (is the server running? it writes one per team in "
            f"{p.parent} when it starts: use --key FILE for a server elsewhere)"
        )
    teams = [name for name in held if name != ADMIN]
    raise CredentialError(
        f"no credential {p.name} in {p.parent}, which holds {', '.join(held)}: is {p.stem!r} one of the run's "
        f"teams ({', '.join(teams) or 'none'})? (use --key FILE for a credential kept elsewhere)"
    )


def ensure(folder: str | os.PathLike, names: Iterable[str]) -> dict[str, Credential]:
    """The credentials of ``names`` in ``folder``, creating (0600, folder 0700) those that do not exist."""
    d = Path(folder)
    d.mkdir(parents=True, exist_ok=True, mode=0o700)
    out = {}
    for name in names:
        path = d / f"{name}.key"
        if path.exists():
            cred = read(path)
            if cred.name != name:
                raise CredentialError(f"credential file {path} is for {cred.name!r}, not {name!r}")
        else:
            cred = Credential(name, secrets.token_hex(32))
            _create_whole(path, f"{cred.name}:{cred.secret}\n")
        out[name] = cred
    return out


def _create_whole(path: Path, text: str) -> None:
    """Create ``path`` (0600) holding ``text``, appearing whole or not at all: a client starting while the server
    writes its key must never read a half-written file (it failed with 'expected name:hexsecret'). Written
    beside it, then linked into place, which fails if the file already exists (as O_EXCL did)."""
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.")
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as f:
            f.write(text)
        os.link(tmp, path)
    finally:
        os.unlink(tmp)


def users_file(folder: str | os.PathLike, creds: Iterable[Credential]) -> str:
    """Zenoh's user/password dictionary for these credentials (written next to them, 0600)."""
    path = Path(folder) / "zenoh-users.txt"
    tmp = path.with_suffix(".tmp")
    fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600)
    with os.fdopen(fd, "w", encoding="utf-8") as f:
        for c in creds:
            f.write(f"{c.name}:{c.secret}\n")
    os.replace(tmp, path)
    return str(path)


def claimed_name(attachment: bytes | None) -> str | None:
    """The name an attachment claims (trust it only once `Verifier.signer_of` accepted the sample)."""
    if not attachment or len(attachment) < 6 or attachment[:4] != _MAGIC:
        return None
    return attachment[5 : 5 + attachment[4]].decode(errors="replace")


class Verifier:
    """Tells, for a received sample, which credential signed it (None: unsigned or forged)."""

    def __init__(self, run: str, creds: dict[str, Credential]):
        self._prefix = run.encode() + b"\0"
        self._keys = {c.name.encode(): c.key for c in creds.values()}

    def signer_of(self, topic: str, payload: bytes, attachment: bytes | None) -> str | None:
        if not attachment or len(attachment) < 6 or attachment[:4] != _MAGIC:
            return None
        n = attachment[4]
        name, mac = attachment[5 : 5 + n], attachment[5 + n :]
        key = self._keys.get(name)
        if key is None or len(mac) != _MAC_BYTES:
            return None
        want = hmac.digest(key, self._prefix + topic.encode() + b"\0" + payload, "sha256")[:_MAC_BYTES]
        return name.decode() if hmac.compare_digest(want, mac) else None
