"""What the referee reports: the game as it stands (`sim.game`), the run's result (``result`` of
``simatch run --json``: score, fouls, cards, winner, goals) and the GameState message on ``game_state``."""

from __future__ import annotations

import json
from typing import TYPE_CHECKING

import numpy as np

from ... import msgs
from ...msgs.game_commands import for_team
from ...msgs.game_commands import name as command_name
from .state import Phase

if TYPE_CHECKING:
    from .referee import MslReferee


def tallies(ref: MslReferee) -> dict[str, dict[str, int]]:
    """Score, fouls and cards per team."""
    d = ref.discipline
    return {
        "score": dict(ref.m.game.score),
        "fouls": {t: ref.log.fouls.get(t, 0) for t in ref.teams},
        "yellow_cards": d.per_team(d.yellow),
        "red_cards": d.per_team(d.red),
    }


def winner(ref: MslReferee) -> str | None:
    score = ref.m.game.score
    a, b = ref.teams
    if score[a] != score[b]:
        return a if score[a] > score[b] else b
    return ref.shootout.winner() if ref.shootout is not None else None


def game(ref: MslReferee) -> dict:
    m = ref.m
    g, obs = m.game, m.obs
    last = m.touches.last
    nxt = g.next_restart
    return {
        "stage": g.stage.name,
        "phase": g.phase.value,
        "clock": round(g.clock, 6),
        "time_left": round(g.time_left, 6),
        **tallies(ref),
        "sent_off": [obs.names[i] for i in ref.discipline.sent_off],
        "commands": {
            t: {
                "match_mode": int(msg.match_mode),
                "match_type": int(msg.match_type),
                "name": command_name(msg.match_mode),
            }
            for t, msg in ref.coach_info.items()
        },
        "reason": g.reason,
        "restart": g.restart.describe() if g.restart is not None else None,
        "next_restart": nxt.describe() if nxt is not None else None,
        "last_touch": obs.names[last] if last >= 0 else "",
        "ball_in_play": g.ball_in_play,
        "paused": g.phase is Phase.PAUSED,
        "manual": not g.auto,
        "shootout": ref.shootout.summary() if ref.shootout is not None else None,
        "attacks": {t: obs.attacks(t) for t in ref.teams},
    }


def result(ref: MslReferee) -> dict:
    g = ref.m.game
    return {
        **tallies(ref),
        "winner": winner(ref) if g.ended else None,
        "ended": g.ended,
        "stage": g.stage.name,
        "clock": round(g.clock, 6),
        "goals": list(ref.goals),
        "disallowed_goals": len(ref.log.of_type("goal_disallowed")),
        "shootout": ref.shootout.summary() if ref.shootout is not None else None,
    }


def game_state(ref: MslReferee, now: float):
    m = ref.m
    g, obs = m.game, m.obs
    first = ref.teams[0]
    nxt = g.next_restart
    stopped = g.phase is Phase.STOPPED and nxt is not None
    spot = nxt if stopped else g.restart
    last = m.touches.last
    t = tallies(ref)

    def per_team(key: str) -> np.ndarray:
        return np.array([t[key][team] for team in ref.teams], dtype=np.int32)

    return msgs.GameState(
        stamp=now,
        stage=g.stage.name,
        phase=g.phase.value,
        clock=g.clock,
        stage_time_left=g.time_left,
        command=int(for_team(g.command, g.command_team, first) if g.command_team else g.command),
        next_command=int(nxt.command_for(first)) if nxt is not None else 0,
        command_team=nxt.team if stopped else g.command_team,
        reason=g.reason,
        teams=list(ref.teams),
        score=per_team("score"),
        yellow_cards=per_team("yellow_cards"),
        red_cards=per_team("red_cards"),
        fouls=per_team("fouls"),
        sent_off=[obs.names[i] for i in ref.discipline.sent_off],
        last_touch=obs.names[last] if last >= 0 else "",
        ball_in_play=g.ball_in_play,
        paused=g.phase is Phase.PAUSED,
        manual=not g.auto,
        ball_x=float(spot.x) if spot is not None else 0.0,
        ball_y=float(spot.y) if spot is not None else 0.0,
        result=json.dumps(result(ref)),
        attacks=[obs.attacks(team) for team in ref.teams],
    )
