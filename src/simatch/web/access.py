"""Who may do what: one secret token per page, printed on the console when the server starts.

A coach page commands only its own team, the referee console commands the game, the replay page only
moves its own timeline, and so does the 3D view (``view3d``: the exact world in 3D, live or recorded). The
token travels in the page's address (``?token=...``) and is checked when the page's WebSocket opens, so a
page that was given the cyan coach's token cannot become magenta's coach by editing its address or its
messages.
"""

from __future__ import annotations

import secrets
from dataclasses import dataclass

LABELS = {"view3d": "3d view"}  # a page's label where it is not its role


@dataclass(frozen=True)
class Grant:
    """What one token allows: a ``role`` ("coach", "referee", "replay" or "view3d") and, for a coach, its team."""

    role: str
    team: str = ""

    @property
    def page(self) -> str:
        """The page's path on the server."""
        return f"/coach/{self.team}" if self.role == "coach" else f"/{self.role}"

    @property
    def label(self) -> str:
        return f"{self.team} coach" if self.role == "coach" else LABELS.get(self.role, self.role)


class Access:
    """The tokens of one server: a coach token per team, one for the referee console, one for replays, one for
    the 3D view."""

    def __init__(self, teams: list[str], live: bool = True, tokens: dict[Grant, str] | None = None):
        grants = []
        if live:
            grants += [Grant("coach", team) for team in teams] + [Grant("referee")]
        grants += [Grant("replay"), Grant("view3d")]
        given = tokens or {}
        self.tokens: dict[Grant, str] = {g: given.get(g) or secrets.token_urlsafe(12) for g in grants}

    def grant(self, token: str | None) -> Grant | None:
        """The grant of ``token``, or None. Compares in constant time, so timing tells nothing."""
        if not token:
            return None
        found = None
        for grant, secret in self.tokens.items():
            if secrets.compare_digest(secret.encode(), token.encode()):
                found = grant
        return found

    def token(self, role: str, team: str = "") -> str:
        return self.tokens[Grant(role, team)]

    def urls(self, base: str) -> dict[str, str]:
        """Every page's address with its token, by label (e.g. "cyan coach")."""
        return {g.label: f"{base}{g.page}?token={t}" for g, t in self.tokens.items()}
