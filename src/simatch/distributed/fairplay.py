"""Fair play between teams: what each team's processes may send and hear, enforced by the server.

Two layers, both driven by the per-team credentials (`credentials`):

* **Zenoh access control** in the server (a Zenoh router): a team's user may subscribe only to what its own
  robots need (its robots' perception, its coach, its team picture, the clock and the lockstep ticks), so
  it cannot read the opponent's perception or plans, nor the ground truth (model states). It may send on
  the keys the server consumes (commands, team strategy info, events, the privileged calls) and on nothing
  that reaches another team: those samples go to the server only.
* **The server's check of every sample it uses** (`FairPlay.check`): the attachment proves which credential
  sent it; a team may command only its own robots, publish only its own team's information, and never call
  set_model_state / set_link_state / apply_wrench (the organiser's ``admin`` credential may). Anything else
  is refused and logged (a ``refused`` event), never applied.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping

from .. import msgs
from ..bus import topics
from . import protocol
from .credentials import ADMIN, Credential, Verifier, claimed_name

#: robot topics a team sends (server-side consumers only)
ROBOT_OUTPUTS = (topics.VEL_CMD, topics.ACTION_CMD, topics.STRATEGY_INFO)
#: the Gazebo-like calls and the referee's operator requests: only the organiser may make them
PRIVILEGED = (topics.SET_MODEL_STATE, topics.SET_LINK_STATE, topics.APPLY_WRENCH, topics.REFEREE_COMMAND)
#: event types a team may add to the run's log (about itself)
TEAM_EVENT_TYPES = frozenset({"strategy_error"})

_MAX_VERDICTS = 4096

_ALL_MESSAGES = [
    "put",
    "delete",
    "declare_subscriber",
    "query",
    "reply",
    "declare_queryable",
    "liveliness_token",
    "liveliness_query",
    "declare_liveliness_subscriber",
]


class Refusal(str):
    """Why a sample was refused; ``who`` is the credential that sent it ("" if none proved it)."""

    who: str = ""

    @classmethod
    def of(cls, who: str, why: str) -> Refusal:
        r = cls(why)
        r.who = who
        return r


class FairPlay:
    """The server's rules: ``teams`` maps each team to its robot ids."""

    def __init__(self, run: str, creds: Mapping[str, Credential], teams: Mapping[str, Iterable[int]]):
        self.run = run
        self.verifier = Verifier(run, dict(creds))
        self.teams = {t: frozenset(ids) for t, ids in teams.items()}
        #: (sender, topic) -> why refused (None: allowed): every rule but the events' depends on these two
        #: only, and a server judges the same few dozen pairs at every tick
        self._verdicts: dict[tuple[str, str], str | None] = {}

    def check(self, topic: str, payload: bytes, attachment: bytes | None) -> Refusal | None:
        """None if the sample may be used, else why not (for `ZenohBus(verifier=...)`)."""
        who = self.verifier.signer_of(topic, payload, attachment)
        if who is None:
            return Refusal.of("", f"unsigned or forged sample on {topic} (no valid credential)")
        return self._judge(who, topic, payload)

    def check_entry(self, attachment: bytes | None, topic: str, payload: bytes) -> Refusal | None:
        """None if an entry of a bundle may be used, else why not (for `ZenohBus(entry_verifier=...)`):
        the bundle's signature, already checked by `check`, names the sender; each entry must be one that
        sender may send on its own."""
        who = claimed_name(attachment)
        if who is None:
            return Refusal.of("", f"entry on {topic} of an unsigned bundle")
        return self._judge(who, topic, payload)

    def _judge(self, who: str, topic: str, payload: bytes) -> Refusal | None:
        if who == ADMIN:
            return None
        if topic == topics.EVENTS:
            why = self.may_send(who, topic, payload)
        else:
            key = (who, topic)
            try:
                why = self._verdicts[key]
            except KeyError:
                why = self.may_send(who, topic, payload)
                if len(self._verdicts) >= _MAX_VERDICTS:  # a sender inventing topics cannot grow it
                    self._verdicts.clear()
                self._verdicts[key] = why
        return None if why is None else Refusal.of(who, why)

    def identify(self, topic: str, payload: bytes, attachment: bytes | None) -> str | None:
        return self.verifier.signer_of(topic, payload, attachment)

    def may_send(self, team: str, topic: str, payload: bytes) -> str | None:
        parts = topic.split("/")
        if len(parts) == 3 and parts[2] in ROBOT_OUTPUTS:
            owner, rid = parts[0], parts[1]
            if owner != team:
                return f"{team} may not command {owner}/{rid} ({parts[2]}): it is not one of its robots"
            if not rid.isdigit() or int(rid) not in self.teams.get(team, ()):
                return f"{team} has no robot {rid} ({topic})"
            return None
        if parts == [team, topics.TEAM_STRATEGY] or (len(parts) >= 2 and parts[0] == team and parts[1] == "lockstep"):
            return None
        if topic in PRIVILEGED:
            return f"{team} may not call {topic}: only the organiser's {ADMIN} credential may"
        if topic == topics.EVENTS:
            try:
                ev = msgs.decode(msgs.GameEvent, payload)
            except msgs.MessageError as exc:
                return f"{team} sent an event that does not decode: {exc}"
            if ev.team != team or ev.type not in TEAM_EVENT_TYPES:
                return (
                    f"{team} may log only its own {', '.join(sorted(TEAM_EVENT_TYPES))} events, "
                    f"not a {ev.type!r} event of team {ev.team!r}"
                )
            return None
        return f"{team} may not publish on {topic}"

    def access_control(self) -> dict:
        """Zenoh's access-control configuration for the server's router (users = credential names)."""
        base = f"{topics.PREFIX}/{self.run}"

        def keys(*rel: str) -> list[str]:
            return [f"{base}/{r}" for r in rel]

        rules = [
            {
                "id": "admin",
                "permission": "allow",
                "flows": ["ingress", "egress"],
                "messages": _ALL_MESSAGES,
                "key_exprs": ["**"],
            }
        ]
        subjects = [{"id": "admin", "usernames": [ADMIN]}]
        policies = [{"rules": ["admin"], "subjects": ["admin"]}]
        for team in self.teams:
            sends = keys(
                *(f"*/*/{leaf}" for leaf in ROBOT_OUTPUTS),
                f"{team}/{topics.TEAM_STRATEGY}",
                topics.EVENTS,
                f"{team}/lockstep/**",
                *PRIVILEGED,
            )
            hears = keys(
                f"{team}/*/{topics.OMNI_VISION}",
                f"{team}/{topics.RECEIVE_FROM_COACH}",
                f"{team}/{topics.TEAM_STRATEGY}",
                topics.CLOCK,
                topics.GAME_STATE,
                protocol.TICKS,
                protocol.END,
                protocol.feeds_of(team),
            )
            asks = keys(protocol.SCENE, protocol.JOIN)
            mine = [
                (f"{team}-send", ["ingress"], ["put"], sends),
                (f"{team}-send-routes", ["egress"], ["declare_subscriber"], sends),
                (f"{team}-hear", ["ingress"], ["declare_subscriber"], hears),
                (f"{team}-hear-data", ["egress"], ["put"], hears),
                (f"{team}-ask", ["ingress"], ["query"], asks),
                (f"{team}-answers", ["egress"], ["reply", "declare_queryable"], asks),
                (f"{team}-alive", ["ingress"], ["liveliness_token"], keys(f"{team}/lockstep/alive/*")),
                (
                    f"{team}-server-alive-watch",
                    ["ingress"],
                    ["declare_liveliness_subscriber", "liveliness_query"],
                    keys(protocol.SERVER_ALIVE),
                ),
                (f"{team}-server-alive", ["egress"], ["liveliness_token", "reply"], keys(protocol.SERVER_ALIVE)),
            ]
            for rid, flows, messages, key_exprs in mine:
                rules.append(
                    {"id": rid, "permission": "allow", "flows": flows, "messages": messages, "key_exprs": key_exprs}
                )
            subjects.append({"id": team, "usernames": [team]})
            policies.append({"rules": [r[0] for r in mine], "subjects": [team]})
        return {
            "enabled": True,
            "default_permission": "deny",
            "rules": rules,
            "subjects": subjects,
            "policies": policies,
        }
